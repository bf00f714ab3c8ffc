"""Type stubs of irad's native module (python/src/lib.rs)."""

import os
from typing import Any, Dict, Iterator, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

_Image = npt.NDArray[np.float32]
_Path = Union[str, "os.PathLike[str]"]

class SettingsError(ValueError):
    """A setting irad refuses; ``argument`` names the keyword argument (the CLI's flag)."""

    argument: str

class Scene:
    """A scene: a built-in's name or a glTF file, loaded."""

    spec: str
    @staticmethod
    def load(spec: _Path, allow_outside_paths: bool = False) -> "Scene": ...
    @property
    def duration(self) -> float: ...
    @property
    def warnings(self) -> List[str]: ...
    def info(self) -> Dict[str, Any]: ...

class Renderer:
    note: Optional[str]
    settings: str
    def __init__(self, scene: Union[Scene, str, None], args: List[str]) -> None: ...
    @property
    def remaining(self) -> Tuple[int, int]: ...
    def __iter__(self) -> "Renderer": ...
    def __next__(
        self,
    ) -> Tuple[int, float, _Image, str, Optional[_Image], Optional[_Image]]: ...

def reference(
    scene: Union[Scene, str, None], args: List[str]
) -> List[Tuple[int, float, _Image]]: ...
def read_image(path: _Path) -> _Image: ...
def write_exr(path: _Path, image: _Image) -> None: ...
def list_frames(folder: _Path) -> Tuple[List[int], List[str]]: ...
def metrics_folders(test: _Path, reference: _Path) -> Tuple[List[int], str]: ...
def metrics_sequence(
    numbers: List[int], test: List[_Image], reference: List[_Image]
) -> str: ...
def metrics_warped(
    numbers: List[int],
    test: List[_Image],
    reference: List[_Image],
    scene: Union[Scene, str],
    fps: float,
    camera: Optional[str] = None,
    allow_outside_paths: bool = False,
) -> str: ...
def metrics_floor(
    numbers: List[int],
    reference: List[_Image],
    half_a: List[_Image],
    half_b: List[_Image],
    spp: Tuple[int, int],
    scene: Union[Scene, str, None] = None,
    fps: float = 24.0,
    camera: Optional[str] = None,
    allow_outside_paths: bool = False,
) -> str: ...
def frame_error(test: _Image, reference: _Image) -> str: ...
def flip(test: _Image, reference: _Image) -> float: ...
def compare(args: List[str]) -> str: ...
def builtins() -> List[Tuple[str, str]]: ...
def adapter(backend: str = "auto") -> str: ...
