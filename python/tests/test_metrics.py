"""irad.metrics gives `irad metrics`'s numbers, from folders or from arrays."""

import json

import numpy as np

import irad
from conftest import cli


def test_metrics_equal_irad_metrics_on_the_same_folders(cli_render, cli_reference, tmp_path):
    cli("metrics", str(cli_render), str(cli_reference), "--scene", "cornell-orbit",
        "--out", str(tmp_path))
    expected = json.loads((tmp_path / "metrics.json").read_text())
    warped_expected = json.loads((tmp_path / "warped.json").read_text())

    from_folders = irad.metrics.sequence(cli_render, cli_reference)
    assert from_folders == expected
    assert expected["flicker_f1"] > 0 and expected["mean_rel_mse"] > 0

    numbers, test = irad.read_frames(cli_render)
    _, ref = irad.read_frames(cli_reference)
    assert numbers == [0, 1, 2, 3]
    assert irad.metrics.sequence(test, ref) == expected
    assert irad.metrics.sequence(np.stack(test), np.stack(ref), frames=numbers) == expected
    assert irad.metrics.flicker(test, ref) == expected["flicker_f1"]
    f0 = expected["frames"][0]
    assert irad.metrics.rel_mse(test[0], ref[0]) == f0["rel_mse"]
    assert irad.metrics.bias(test[0], ref[0]) == f0["bias"]
    assert irad.metrics.flip(test[0], ref[0]) == f0["flip"]

    assert irad.metrics.warped(test, ref, "cornell-orbit") == warped_expected
    assert irad.metrics.warped(cli_render, cli_reference, irad.Scene.load("cornell-orbit"),
                               fps=24) == warped_expected


def test_frames_from_another_renderer_as_float64_arrays(cli_render, cli_reference):
    """Any renderer's frames: float64, from a list; the same numbers as float32."""
    _, test = irad.read_frames(cli_render)
    _, ref = irad.read_frames(cli_reference)
    a = irad.metrics.sequence([t.astype(np.float64) for t in test], ref)
    b = irad.metrics.sequence(test, ref)
    assert a == b


def test_the_floor_of_identical_halves_is_zero_and_of_different_ones_is_not(cli_reference):
    _, ref = irad.read_frames(cli_reference)
    twin = irad.metrics.floor(ref, (ref, ref), spp=(4, 4), scene="cornell-orbit")
    assert twin["flicker_f1"] == 0 and twin["rel_mse"] == 0 and twin["warped_f1"] == 0
    noisy = [r * np.float32(1.1) for r in ref]
    f = irad.metrics.floor(ref, (ref, noisy), spp=(4, 4))
    assert f["rel_mse"] > 0 and f["warped_f1"] is None
    assert [x["frame"] for x in f["frames"]] == [0, 1, 2, 3]


def test_write_exr_round_trips():
    img = np.random.default_rng(1).random((5, 7, 3), dtype=np.float32)
    import tempfile, os
    with tempfile.TemporaryDirectory() as d:
        irad.write_exr(os.path.join(d, "frame_0000.exr"), img)
        assert np.array_equal(irad.read_image(os.path.join(d, "frame_0000.exr")), img)
