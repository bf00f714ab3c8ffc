"""Shared fixtures: the CLI binary the package's results are held to, and small runs of it."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# Tiny settings: every test here is about agreement with the CLI, not about images.
SIZE = "32x32"
FRAMES = "0..4"


def irad_bin() -> Path:
    """`irad` as built by `cargo build --release` (or IRAD_BIN)."""
    path = Path(os.environ.get("IRAD_BIN", ROOT / "target" / "release" / "irad"))
    if not path.exists():
        pytest.fail(f"{path}: build the CLI first (cargo build --release) or set IRAD_BIN")
    return path


def cli(*args: str, cwd=None) -> str:
    """Runs `irad ARGS`, failing the test with its stderr on an error."""
    p = subprocess.run(
        [str(irad_bin()), *args], capture_output=True, text=True, cwd=cwd
    )
    assert p.returncode == 0, f"irad {' '.join(args)}: {p.stderr}"
    return p.stdout


def read_jsonl(path: Path):
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


@pytest.fixture(scope="session")
def cli_render(tmp_path_factory):
    """`irad render` of cornell-orbit frames 0..4 at 32x32, 16 VPLs, cdf, seed 3."""
    out = tmp_path_factory.mktemp("render")
    cli(
        "render", "cornell-orbit", "--frames", FRAMES, "--size", SIZE,
        "--vpls", "16", "--sampler", "cdf", "--seed", "3", "--out", str(out),
        "--overwrite",
    )
    return out


@pytest.fixture(scope="session")
def cli_reference(tmp_path_factory):
    """`irad reference` of the same frames, 8 samples a pixel."""
    out = tmp_path_factory.mktemp("reference")
    cli(
        "reference", "cornell-orbit", "--frames", FRAMES, "--size", SIZE,
        "--spp", "8", "--out", str(out), "--overwrite",
    )
    return out
