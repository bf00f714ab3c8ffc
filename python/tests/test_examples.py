"""The examples run (at tiny settings: IRAD_EXAMPLE_TINY=1)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def run(script, *args, cwd):
    env = dict(os.environ, IRAD_EXAMPLE_TINY="1", MPLBACKEND="Agg")
    p = subprocess.run([sys.executable, str(EXAMPLES / script), *args], cwd=cwd, env=env,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return p.stdout


def test_compare_samplers_plots_cdf_and_mh(tmp_path):
    pytest.importorskip("matplotlib")
    out = run("compare_samplers.py", "--out", "plot.png", cwd=tmp_path)
    assert "cdf" in out and "mh" in out and "flicker F1" in out
    assert (tmp_path / "plot.png").stat().st_size > 1000


def test_flicker_of_my_renderer_scores_a_folder(tmp_path, cli_render, cli_reference):
    # Frames from "another renderer" (a folder of EXR) against a given reference folder...
    out = run("flicker_of_my_renderer.py", str(cli_render), "--reference", str(cli_reference),
              cwd=tmp_path)
    assert "warped F1" in out and "4 frames of cornell-orbit at 32x32" in out
    # ...and with no folder, its stand-in against a reference irad traces.
    out = run("flicker_of_my_renderer.py", cwd=tmp_path)
    assert "tracing irad's reference" in out and "warped F1" in out
