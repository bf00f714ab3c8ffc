"""Bad arguments are Python exceptions naming the argument; none is a panic."""

import numpy as np
import pytest

import irad


@pytest.mark.parametrize(
    "kwargs, argument",
    [
        (dict(vpls=0), "vpls"),
        (dict(vpls="many"), "vpls"),
        (dict(size=(0, 16)), "size"),
        (dict(size=(16, 16, 3)), "size"),
        (dict(sampler="nope"), "sampler"),
        (dict(ism_size=5), "ism_size"),
        (dict(fps=float("nan")), "fps"),
        (dict(exposure=-1.0), "exposure"),
        (dict(clamp=float("inf")), "clamp"),
        (dict(frames=range(0, 10, 2)), "frames"),
        (dict(frames=(5, 5)), "frames"),
        (dict(camera=(0, 0, 1)), "camera"),
        (dict(camera=((0, 0, 1), (0, 0, 1), 40)), "camera"),
        (dict(aa=9), "aa"),
    ],
)
def test_a_bad_setting_raises_value_error_naming_it(kwargs, argument):
    with pytest.raises(ValueError) as e:
        irad.render("cornell", **kwargs)
    assert isinstance(e.value, irad.SettingsError)
    assert argument in str(e.value), str(e.value)
    assert e.value.argument == argument or argument == "frames"


def test_an_unknown_keyword_is_a_type_error():
    with pytest.raises(TypeError, match="unexpected keyword argument 'vlps'"):
        irad.render("cornell", vlps=8)


def test_a_missing_scene_is_file_not_found():
    with pytest.raises(FileNotFoundError, match="no_such.gltf"):
        irad.Scene.load("no_such.gltf")
    with pytest.raises(FileNotFoundError, match="did you mean 'cornell'"):
        irad.render("cornel", frames=0)
    with pytest.raises(FileNotFoundError):
        irad.metrics.sequence("no/such/folder", "no/such/reference")


def test_reference_and_metrics_name_their_arguments():
    with pytest.raises(ValueError, match="spp"):
        irad.reference("cornell", spp=0)
    img = np.zeros((4, 4, 3), np.float32)
    with pytest.raises(ValueError, match="test"):
        irad.metrics.rel_mse(np.zeros((4, 4)), img)
    with pytest.raises(ValueError, match="image sizes differ"):
        irad.metrics.frame_error(np.zeros((4, 5, 3)), img)
    with pytest.raises(ValueError, match="fps"):
        irad.metrics.warped([img, img], [img, img], "cornell", fps=0)
    with pytest.raises(ValueError, match="reference"):
        irad.metrics.sequence([img, img], [img])


def test_ctrl_c_stops_a_reference_between_frames():
    import os, signal, threading, time

    # Python leaves SIGINT ignored when its process started with it ignored, as a job started
    # in the background of a non-interactive shell does (`.ci/run &`): there the timer's
    # signal never became a KeyboardInterrupt. So Python's own handler, for this test.
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    try:
        start = time.time()
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            # About 5 ms a frame here: 2000 frames would take 10 s (at 1 spp, 0.5 ms a frame,
            # all of them took about 1 s).
            irad.reference("cornell-orbit", frames=range(0, 2000), spp=16, size=(32, 32))
        assert time.time() - start < 10
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, old)
