"""Error and flicker of any renderer's frames against a reference, as ``irad metrics`` and
``irad compare`` measure them (docs/math.md, "Metrics").

Sequences are a folder of ``frame_FFFF.exr`` (or ``.png``, sRGB decoded to linear), a list of
H x W x 3 linear RGB arrays, or one N x H x W x 3 array. Frame numbers come from the folder's
file names, else from ``frames`` (default ``0..N``); flicker needs consecutive frames.
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _irad

Images = Union[str, "os.PathLike[str]", Sequence[np.ndarray], np.ndarray]

__all__ = [
    "sequence",
    "warped",
    "floor",
    "frame_error",
    "rel_mse",
    "bias",
    "flip",
    "flicker",
]


def _bad(argument: str, text: str) -> Exception:
    from . import _bad

    return _bad(argument, text)


def _image(a: Any, what: str) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float32)
    if a.ndim != 3 or a.shape[2] != 3:
        raise _bad(
            what, f"an image is H x W x 3 (linear RGB), not shape {a.shape}"
        )
    return a


def _images(x: Images, what: str) -> Tuple[Optional[List[int]], List[np.ndarray]]:
    if isinstance(x, (str, os.PathLike)):
        numbers, paths = _irad.list_frames(os.fspath(x))
        return list(numbers), [_irad.read_image(p) for p in paths]
    if isinstance(x, np.ndarray) and x.ndim == 4:
        return None, [_image(i, what) for i in x]
    if isinstance(x, np.ndarray):
        raise _bad(
            what, f"frames are a folder, a list of H x W x 3 arrays or an N x H x W x 3 array, not shape {x.shape}"
        )
    return None, [_image(i, what) for i in x]


def _pair(
    test: Images, reference: Images, frames: Optional[Sequence[int]]
) -> Tuple[List[int], List[np.ndarray], List[np.ndarray]]:
    tn, t = _images(test, "test")
    rn, r = _images(reference, "reference")
    if tn is not None and rn is not None:
        # Two folders: matched by frame number, as `irad metrics` matches them.
        by_number = dict(zip(rn, r))
        missing = [n for n in tn if n not in by_number]
        if missing:
            raise _bad(
                "reference", f"frame {missing[0]} of test has no counterpart"
            )
        r = [by_number[n] for n in tn]
        rn = tn
    numbers = list(frames) if frames is not None else (tn or rn or list(range(len(t))))
    if len(t) != len(r) or len(numbers) != len(t) or not t:
        raise _bad(
            "reference", f"{len(t)} test frames, {len(r)} reference frames and {len(numbers)} frame numbers"
        )
    return numbers, t, r


def sequence(
    test: Images, reference: Images, frames: Optional[Sequence[int]] = None
) -> Dict[str, Any]:
    """``irad metrics TEST REFERENCE``: per frame relMSE, RMSE, bias, FLIP and flicker, and their
    means, flicker F1 and RMS, temporal variance and bias (the fields of its metrics.json)."""
    folder = (str, os.PathLike)
    if isinstance(test, folder) and isinstance(reference, folder) and frames is None:
        _, m = _irad.metrics_folders(os.fspath(test), os.fspath(reference))
        return json.loads(m)
    numbers, t, r = _pair(test, reference, frames)
    return json.loads(_irad.metrics_sequence(numbers, t, r))


def warped(
    test: Images,
    reference: Images,
    scene: Any,
    fps: float = 24.0,
    frames: Optional[Sequence[int]] = None,
    camera: Any = None,
    allow_outside_paths: bool = False,
) -> Dict[str, Any]:
    """``irad metrics ... --scene``: flicker F1 with each pixel followed along the scene's motion
    (frame f at time f / fps, seen from ``camera`` if the frames were rendered with one):
    ``f1``, ``kept`` (the fraction of pixels not disoccluded) and per frame pair (F1, kept)."""
    from . import _camera_value, _scene

    numbers, t, r = _pair(test, reference, frames)
    cam = None if camera is None else _camera_value(camera)
    s = _scene(scene)
    if s is None:
        raise _bad("scene", "warped flicker needs the scene the frames show")
    return json.loads(
        _irad.metrics_warped(numbers, t, r, s, float(fps), cam, allow_outside_paths)
    )


def floor(
    reference: Images,
    halves: Tuple[Images, Images],
    spp: Tuple[int, int],
    frames: Optional[Sequence[int]] = None,
    scene: Any = None,
    fps: float = 24.0,
    camera: Any = None,
) -> Dict[str, Any]:
    """The reference's own noise floor (``irad compare``'s): what a perfect renderer would measure
    against ``reference``, the spp-weighted mean of two independent halves ``halves`` of ``spp``
    samples a pixel each. Flicker F1 and RMS, relMSE, per frame, and warped F1 with ``scene``."""
    from . import _camera_value, _scene

    numbers, r, a = _pair(reference, halves[0], frames)
    _, _, b = _pair(reference, halves[1], numbers)
    cam = None if camera is None else _camera_value(camera)
    s = None if scene is None else _scene(scene)
    return json.loads(
        _irad.metrics_floor(
            numbers, r, a, b, (int(spp[0]), int(spp[1])), s, float(fps), cam
        )
    )


def frame_error(test: Any, reference: Any) -> Dict[str, float]:
    """relMSE, RMSE, bias and relative bias of one image against another."""
    return json.loads(
        _irad.frame_error(_image(test, "test"), _image(reference, "reference"))
    )


def rel_mse(test: Any, reference: Any) -> float:
    """``mean over pixels and channels of (I - R)^2 / (R^2 + 0.01)``."""
    return frame_error(test, reference)["rel_mse"]


def bias(test: Any, reference: Any) -> float:
    """``mean lum(I) - mean lum(R)``."""
    return frame_error(test, reference)["bias"]


def flip(test: Any, reference: Any) -> float:
    """FLIP (NVIDIA's perceptual difference, on the tone-mapped images) as ``irad metrics``."""
    return _irad.flip(_image(test, "test"), _image(reference, "reference"))


def flicker(
    test: Images, reference: Images, frames: Optional[Sequence[int]] = None
) -> float:
    """Flicker F1: mean over frame pairs of ``mean_p |e_t - e_(t-1)|``, e = lum(test) - lum(ref)."""
    return sequence(test, reference, frames)["flicker_f1"]
