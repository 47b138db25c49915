# Type stubs of the Python package vpm (docs/python.md).
import os
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Literal, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
PathLike = Union[str, os.PathLike]
ImageLike = Union["Image", PathLike, Any]  # a path, a nibabel image, or a vpm.Image
Progress = Union[None, bool, Callable[[str], Any]]

class NumericalError(RuntimeError): ...

class Mesh:
    def __init__(self, vertices: ArrayLike, tets: ArrayLike, point_data: Optional[Mapping[str, ArrayLike]] = ...,
                 cell_data: Optional[Mapping[str, ArrayLike]] = ...) -> None: ...
    vertices: npt.NDArray[np.float64]
    @property
    def tets(self) -> npt.NDArray[np.int32]: ...
    @property
    def num_vertices(self) -> int: ...
    @property
    def num_tets(self) -> int: ...
    @property
    def point_data(self) -> dict[str, npt.NDArray[np.float64]]: ...
    @property
    def cell_data(self) -> dict[str, npt.NDArray[np.float64]]: ...
    def set_point_field(self, name: str, values: ArrayLike, integer: bool = ...) -> None: ...
    def set_cell_field(self, name: str, values: ArrayLike, integer: bool = ...) -> None: ...
    def copy(self) -> Mesh: ...

class Image:
    def __init__(self, data: ArrayLike, affine: ArrayLike) -> None: ...
    @property
    def data(self) -> npt.NDArray[np.float32]: ...
    @property
    def affine(self) -> npt.NDArray[np.float64]: ...
    @property
    def shape(self) -> tuple[int, int, int]: ...
    @property
    def spacing(self) -> list[float]: ...
    affine_source: str
    path: str

class RatioStats:
    mean_abs_dev: float
    std_log: float
    p99_abs_log: float
    max_abs_log: float
    min: float
    max: float
    def to_dict(self) -> dict[str, Any]: ...

class MapMetrics:
    inverted_tets: int
    vertex_volume_ratio: RatioStats
    tet_volume_ratio: RatioStats
    boundary_max_radius_error: float
    def to_dict(self) -> dict[str, Any]: ...

class Report:
    def to_dict(self) -> dict[str, Any]: ...

class MapReport(Report):
    device: str
    initial: MapMetrics
    final: MapMetrics
    converged: bool
    input_vertices: int
    input_tets: int
    seconds: float

class SurfaceMetrics:
    flipped_faces: int
    face_area_ratio: RatioStats
    vertex_area_ratio: RatioStats
    max_radius_error: float
    def to_dict(self) -> dict[str, Any]: ...

class SurfaceMapReport(Report):
    initial: SurfaceMetrics
    final: SurfaceMetrics
    converged: bool
    seconds: float

class InitialMapReport(Report):
    device: str
    folds_before_untangle: int
    inserted_vertices: int

class RegistrationReport(Report):
    device: str
    landmarks: int
    landmark_rms_error: float
    landmark_max_error: float
    max_normal_velocity: float
    inverted_tets: int
    metrics: MapMetrics

class Elements:
    def __init__(self, level: int = ..., shells: int = ..., samples: int = ..., layout: str = ...) -> None: ...
    @property
    def size(self) -> int: ...
    def __len__(self) -> int: ...
    @property
    def samples(self) -> npt.NDArray[np.float64]: ...
    def centres(self) -> npt.NDArray[np.float64]: ...
    def element_of(self, points: ArrayLike) -> npt.NDArray[np.int32]: ...
    def definition(self) -> dict[str, Any]: ...
    def write(self, path: str) -> None: ...

class ElementTable:
    subject: str
    @property
    def features(self) -> dict[str, dict[str, Any]]: ...
    @property
    def labels(self) -> dict[int, npt.NDArray[np.float64]]: ...
    def definition(self) -> dict[str, Any]: ...
    def write(self, path: str) -> None: ...

@dataclass
class Comparison:
    z: npt.NDArray[np.float64]
    patient: npt.NDArray[np.float64]
    cluster: npt.NDArray[np.int32]
    reference_mean: npt.NDArray[np.float64]
    reference_std: npt.NDArray[np.float64]
    clusters: list[dict[str, Any]]
    threshold_used: float
    summary: dict[str, Any]
    def to_dict(self) -> dict[str, Any]: ...

def devices() -> list[dict[str, Any]]: ...
def select_device(spec: Optional[str]) -> str: ...
def device_name(spec: Optional[str] = ...) -> str: ...
def read_mesh(path: str) -> Mesh: ...
def write_mesh(path: str, mesh: Mesh, ascii: bool = ...) -> None: ...
def validate(mesh: Mesh, source: str = ...) -> dict[str, Any]: ...
def read_image(path: str) -> Image: ...
def write_nifti(path: str, image: Image) -> None: ...
def read_table(path: str) -> ElementTable: ...
def read_label_names(path: str) -> dict[int, str]: ...
def to_native(mesh: Mesh, points: ArrayLike) -> npt.NDArray[np.float64]: ...
def to_image(mesh: Mesh, elements: Elements, values: ArrayLike, grid: Image) -> Image: ...
def image(source: ImageLike, affine: Optional[ArrayLike] = ...) -> Image: ...
def mesh_image(source: Union[ImageLike, ArrayLike], labels: Optional[Union[ImageLike, ArrayLike]] = ..., *,
               affine: Optional[ArrayLike] = ..., progress: Progress = ..., threshold: float = ...,
               select_labels: Sequence[int] = ..., target_vertices: int = ..., max_volume: float = ...,
               smooth: float = ..., close_at_border: bool = ..., radius_edge: float = ...,
               min_dihedral: float = ...) -> tuple[Mesh, dict[str, Any]]: ...
def initial_map(vertices: Union[Mesh, ArrayLike], tets: Optional[ArrayLike] = ..., *,
                sphere: Literal["area", "conformal"] = ..., sphere_start: Literal["auto", "progressive", "axial"] = ...,
                sphere_solve: Literal["auto", "host", "device"] = ...,
                untangle: Literal["never", "if-folded", "always"] = ..., split: bool = ..., source: str = ...,
                device: Optional[str] = ...) -> tuple[Mesh, InitialMapReport]: ...
def map_to_ball(vertices: Union[Mesh, ArrayLike], tets: Optional[ArrayLike] = ..., *, progress: Progress = ...,
                rounds: int = ..., tolerance: float = ...,
                sphere: Literal["area", "conformal"] = ..., sphere_start: Literal["auto", "progressive", "axial"] = ...,
                sphere_solve: Literal["auto", "host", "device"] = ...,
                boundary: Literal["auto", "slide", "fixed"] = ...,
                preconditioner: Literal["auto", "jacobi", "amg"] = ..., rk_steps: int = ..., max_seconds: float = ...,
                source: str = ...,
                device: Optional[str] = ...) -> tuple[Mesh, MapReport]: ...
def read_surface(path: PathLike) -> tuple[np.ndarray, np.ndarray]: ...
def read_overlay(path: PathLike) -> np.ndarray: ...
def write_surface(path: PathLike, vertices: ArrayLike, faces: ArrayLike) -> None: ...
def map_to_sphere(vertices: ArrayLike, faces: ArrayLike, *, progress: Progress = ..., rounds: int = ...,
                  tolerance: float = ..., sphere: Literal["area", "conformal"] = ...,
                  sphere_start: Literal["auto", "progressive", "axial"] = ..., max_seconds: float = ...,
                  source: str = ...) -> tuple[np.ndarray, SurfaceMapReport]: ...
def map_to_disk(vertices: ArrayLike, faces: ArrayLike, *, progress: Progress = ..., rounds: int = ...,
                tolerance: float = ..., max_seconds: float = ...,
                source: str = ...) -> tuple[np.ndarray, SurfaceMapReport]: ...
def register_on_sphere(vertices: ArrayLike, faces: ArrayLike, landmarks: Optional[ArrayLike] = ...,
                       targets: Optional[ArrayLike] = ..., *, values: Optional[ArrayLike] = ...,
                       template: Optional[tuple[ArrayLike, ArrayLike, ArrayLike]] = ...,
                       steps: int = ..., width_factor: float = ..., rigid: bool = ...,
                       restore: bool = ..., iterations: int = ...,
                       widths: Sequence[float] = ...) -> tuple[np.ndarray, SurfaceMapReport]: ...
def register_in_disk(vertices: ArrayLike, faces: ArrayLike, landmarks: ArrayLike, targets: ArrayLike, *,
                     steps: int = ..., width_factor: float = ..., rigid: bool = ...,
                     restore: bool = ...) -> tuple[np.ndarray, SurfaceMapReport]: ...
def mean_curvature(vertices: ArrayLike, faces: ArrayLike) -> np.ndarray: ...
def locate_on_sphere(vertices: ArrayLike, faces: ArrayLike, points: ArrayLike) -> tuple[np.ndarray, np.ndarray]: ...
def register(mesh: Mesh, *, landmarks: Optional[ArrayLike] = ..., targets: Optional[ArrayLike] = ...,
             template: Optional[Mesh] = ..., image: Optional[ImageLike] = ..., template_image: Optional[ImageLike] = ...,
             template_landmarks: Literal["regions", "moments"] = ..., exclude_labels: Sequence[int] = ...,
             preset: Optional[Literal["landmarks", "standard", "accurate"]] = ...,
             dense_iterations: Optional[int] = ..., dense_force: Literal["labels", "image", "both"] = ...,
             rk_steps: int = ..., width: Optional[float] = ..., width_factor: float = ...,
             flow_boundary: Literal["tangent", "samples", "none"] = ..., field: Literal["per-step", "steady"] = ...,
             rigid: bool = ..., untangle: bool = ..., restore: bool = ..., max_seconds: float = ...,
             device: Optional[str] = ..., progress: Progress = ...) -> tuple[Mesh, RegistrationReport]: ...
def elements(level: int = ..., shells: int = ..., samples: int = ...,
             layout: Literal["shells", "graded"] = ...) -> Elements: ...
def sample(mesh: Mesh, images: Optional[Mapping[str, ImageLike]] = ..., labels: Optional[ImageLike] = ..., *,
           elements: Optional[Elements] = ..., subject: str = ...) -> ElementTable: ...
def compare(normals: Iterable[Union[ElementTable, str]], patient: Union[ElementTable, str], feature: str, *,
            normalisation: Literal["proportional", "none"] = ..., threshold: float = ..., fdr: float = ...,
            min_cluster: int = ..., extend: float = ..., relative_extent: float = ..., peak: float = ...,
            sign: Literal["both", "hyper", "hypo"] = ..., test: Literal["z", "crawford-howell"] = ...,
            smooth: int = ..., shrink: float = ..., covariates: Optional[Sequence[str]] = ...,
            participants: str = ..., image_covariate: str = ..., tfce_level: float = ...,
            calibration: Optional[Union[dict, str, os.PathLike]] = ...) -> Comparison: ...
def calibrate(normals: Iterable[Union[ElementTable, str]], feature: str, *, rate: float = ...,
              peak: Union[float, Literal["auto"]] = ..., tfce: bool = ...,
              normalisation: Literal["proportional", "none"] = ..., threshold: float = ..., fdr: float = ...,
              extend: float = ..., relative_extent: float = ..., sign: Literal["both", "hyper", "hypo"] = ...,
              test: Literal["z", "crawford-howell"] = ..., smooth: int = ..., shrink: float = ...,
              covariates: Optional[Sequence[str]] = ..., participants: str = ...,
              image_covariate: str = ...) -> dict: ...
