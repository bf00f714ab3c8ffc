"""irad from Python: instant radiosity for animation sequences, numpy frames in and out.

Keyword arguments are the command line's flags (``vpls=64`` is ``--vpls 64``,
``ism_size=64`` is ``--ism-size 64``, ``no_reuse=True`` is ``--no-reuse``), parsed and checked
by irad's own settings types, with the CLI's defaults; ``irad render --help`` lists them. A
setting irad refuses raises :class:`SettingsError` (a ``ValueError``) whose ``argument`` names
the keyword; a scene that is neither a built-in nor a file raises ``FileNotFoundError``.

Every render in a process shares one GPU device; the GIL is released while a frame renders.
See docs/python.md.
"""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _irad
from ._irad import Scene, SettingsError, adapter, builtins, read_image, write_exr
from . import metrics

__all__ = [
    "Scene",
    "Frame",
    "SettingsError",
    "CompareTable",
    "render",
    "render_iter",
    "reference",
    "compare",
    "metrics",
    "read_image",
    "read_frames",
    "write_exr",
    "builtins",
    "adapter",
]

SceneArg = Union[Scene, str, "os.PathLike[str]", None]
FramesArg = Union[range, Tuple[int, int], int, str, None]


@dataclass
class Frame:
    """One rendered frame.

    ``image`` is linear RGB, float32, H x W x 3 (row 0 at the top): the pixels of the CLI's
    ``frame_FFFF.exr``. ``record`` is the frame's line of ``frames.jsonl`` (``irad reference``
    frames have none). ``direct`` and ``indirect`` are set with ``components=True``.
    """

    index: int
    time: float
    image: np.ndarray
    record: Optional[Dict[str, Any]] = None
    direct: Optional[np.ndarray] = None
    indirect: Optional[np.ndarray] = None


def _bad(argument: str, text: str) -> SettingsError:
    """A SettingsError naming ``argument``."""
    e = SettingsError(f"{argument}: {text}")
    e.argument = argument
    return e


def _frames_value(frames: FramesArg) -> Optional[str]:
    if frames is None:
        return None
    if isinstance(frames, range):
        if frames.step != 1:
            raise _bad("frames", "a range of consecutive frames (step 1)")
        return f"{frames.start}..{frames.stop}"
    if isinstance(frames, (tuple, list)):
        if len(frames) != 2:
            raise _bad("frames", "(start, end), a range, N or 'A..B'")
        return f"{int(frames[0])}..{int(frames[1])}"
    if isinstance(frames, bool):
        raise _bad("frames", "(start, end), a range, N or 'A..B'")
    return str(frames)


def _camera_value(camera: Any) -> str:
    """``(eye, target, fov)`` as ``x,y,z:x,y,z:fov``; a string as it is."""
    if isinstance(camera, str):
        return camera
    try:
        eye, target, fov = camera
        return "{}:{}:{}".format(
            ",".join(repr(float(v)) for v in eye),
            ",".join(repr(float(v)) for v in target),
            repr(float(fov)),
        )
    except (TypeError, ValueError):
        raise _bad("camera", "(eye, target, fov) or 'x,y,z:x,y,z:fov'") from None


def _args(settings: Dict[str, Any]) -> List[str]:
    """Keyword arguments as the command line's flags."""
    out: List[str] = []
    for name, value in settings.items():
        if value is None or value is False:
            continue
        flag = "--" + name.replace("_", "-")
        if value is True:
            out.append(flag)
            continue
        if name == "frames":
            value = _frames_value(value)
        elif name == "camera":
            value = _camera_value(value)
        elif name == "size" and isinstance(value, (tuple, list)):
            if len(value) != 2:
                raise _bad("size", "(width, height) or 'WxH'")
            value = f"{value[0]}x{value[1]}"
        elif isinstance(value, (list, tuple)):
            value = ",".join(str(v) for v in value)
        elif isinstance(value, os.PathLike):
            value = os.fspath(value)
        elif isinstance(value, float):
            # (numpy's float64 is a float whose repr is "np.float64(...)")
            value = repr(float(value))
        out += [flag, str(value)]
    return out


def _scene(scene: SceneArg) -> Union[Scene, str, None]:
    if scene is None or isinstance(scene, Scene):
        return scene
    return os.fspath(scene)


def render_iter(
    scene: SceneArg = None,
    frames: FramesArg = None,
    **settings: Any,
) -> Iterator[Frame]:
    """Renders ``frames`` of ``scene`` as ``irad render`` does, yielding each frame as it is
    done (nothing is written; memory stays flat over any number of frames).

    ``scene``: a :class:`Scene`, a built-in's name or a glTF path (default: the CLI's,
    ``cornell-orbit``). ``frames``: ``range(a, b)``, ``(a, b)``, ``n`` or ``"a..b"`` (default:
    the whole animation, at most 2400 frames). Other keywords are ``irad render``'s flags:
    ``sampler="cdf"``, ``vpls=256``, ``size=(256, 256)``, ``seed=1``, ``fps=24``, ...

    The settings are checked (and the scene loaded, the pipeline built) before this returns.
    """
    r = _irad.Renderer(_scene(scene), _args(dict(settings, frames=frames)))
    if r.note:
        warnings.warn(r.note, stacklevel=2)
    return _frames_of(r)


def _frames_of(r: Any) -> Iterator[Frame]:
    for index, time, image, record, direct, indirect in r:
        yield Frame(index, time, image, json.loads(record), direct, indirect)


def render(
    scene: SceneArg = None,
    frames: FramesArg = None,
    **settings: Any,
) -> List[Frame]:
    """Renders ``frames`` of ``scene`` (see :func:`render_iter`) and returns them all."""
    return list(render_iter(scene, frames, **settings))


def reference(
    scene: SceneArg = None,
    frames: FramesArg = None,
    spp: int = 256,
    **settings: Any,
) -> List[Frame]:
    """Path-traces the ground truth of ``frames`` of ``scene`` as ``irad reference`` does
    (CPU, ``spp`` samples a pixel; default scene ``cornell``, default frames ``0``). Other
    keywords: ``size``, ``seed``, ``fps``, ``camera``, ``environment``."""
    args = _args(dict(settings, frames=frames, spp=spp))
    out = _irad.reference(_scene(scene), args)
    return [Frame(index, time, image) for index, time, image in out]


def read_frames(folder: Union[str, "os.PathLike[str]"]) -> Tuple[List[int], List[np.ndarray]]:
    """A folder's ``frame_FFFF.exr`` (or ``.png``) files: (frame numbers, images)."""
    numbers, paths = _irad.list_frames(os.fspath(folder))
    return list(numbers), [read_image(p) for p in paths]


class CompareTable(list):
    """``irad compare``'s table: one dict per run (sampler, VPL count, knob) with its means,
    ready for ``pandas.DataFrame``. ``frames``: metrics.csv's rows (one per run and frame);
    ``floor``: the reference's noise floor; ``out``: the folder; ``report``: its report.html;
    ``data``: metrics.json whole."""

    out: str
    report: str
    frames: List[Dict[str, Any]]
    floor: Dict[str, Any]
    data: Dict[str, Any]


def _number(v: str) -> Any:
    if v == "":
        return None
    for kind in (int, float):
        try:
            return kind(v)
        except ValueError:
            pass
    return v


def compare(scene: SceneArg = None, **settings: Any) -> CompareTable:
    """Runs ``irad compare`` (samplers x VPL counts against a cached reference; keywords are
    its flags: ``samplers=["cdf", "mh"]``, ``vpls=[64, 256]``, ``frames``, ``spp``, ``out``,
    ...), writes its outputs into ``out`` and returns its table (:class:`CompareTable`)."""
    import csv

    if isinstance(scene, Scene):
        scene = scene.spec
    args = _args(settings)
    if scene is not None:
        args.append(os.fspath(scene))
    out = os.fspath(_irad.compare(args))
    with open(os.path.join(out, "metrics.json")) as f:
        data = json.load(f)
    with open(os.path.join(out, "metrics.csv"), newline="") as f:
        rows = [{k: _number(v) for k, v in r.items()} for r in csv.DictReader(f)]
    table = CompareTable(_summary(run) for run in data["runs"])
    table.out = out
    table.report = os.path.join(out, "report.html")
    table.frames = rows
    table.floor = data["floor"]
    table.data = data
    return table


def _summary(run: Dict[str, Any]) -> Dict[str, Any]:
    """A run of metrics.json as one flat row: its scalars, its metrics' means (``mean_rel_mse``,
    ``flicker_f1``, ...) and its warped flicker's (``warped_f1``, ``warped_kept``); the per-frame
    lists are in :attr:`CompareTable.frames`."""
    row: Dict[str, Any] = {}
    for k, v in run.items():
        if isinstance(v, dict):
            for k2, v2 in v.items():
                if not isinstance(v2, (list, dict)):
                    row[k2 if k == "metrics" else f"{k}_{k2}"] = v2
        elif not isinstance(v, list):
            row[k] = v
    return row
