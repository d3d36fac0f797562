# SPDX-License-Identifier: BSD-3-Clause
from typing import Any, Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class DacpoError(RuntimeError):
    status: int
    status_name: str
    message: str
    def __init__(self, status: int, status_name: str, message: str) -> None: ...

class OrientResult:
    stats: Dict[str, Any]
    component_labels: npt.NDArray[np.int32]
    block_labels: npt.NDArray[np.int32]
    block_flips: npt.NDArray[np.uint8]
    confidence: npt.NDArray[np.float32]
    seconds: float

def default_params() -> Dict[str, Any]: ...
def orient(
    points: npt.ArrayLike,
    normals: Optional[npt.ArrayLike] = ...,
    *,
    progress: Optional[Callable[[str, float], Optional[bool]]] = ...,
    threads: int = ...,
    # scripts/param_table.py: begin KEYWORDS
    k: int = ...,
    normal_k: int = ...,
    num_blocks: int = ...,
    ring_hops: int = ...,
    dipole_c: float = ...,
    dipole_orders: int = ...,
    dipole_neighbors: int = ...,
    dipole_final_sweep: int = ...,
    ipsr_enabled: bool = ...,
    ipsr_max_iterations: int = ...,
    edge_weight: Union[str, int] = ...,
    solver_time_limit: float = ...,
    seed: int = ...,
    num_threads: int = ...,
    disconnected: Union[str, int] = ...,
    vcr_image_size: int = ...,
    vcr_views: int = ...,
    dipole_restarts: int = ...,
    weak_edge_fraction: float = ...,
    sign_policy: Union[str, int] = ...,
    dipole_two_sheet: float = ...,
    dipole_layers: float = ...,
    dipole_sides: float = ...,
    cue_anchor: float = ...,
    dipole_c_thin: float = ...,
    adaptive_normals: bool = ...,
    scan_kind: Union[str, int] = ...,
    seam_dipole: float = ...,
    surface_vote: int = ...,
    # scripts/param_table.py: end
    viewpoint: Sequence[float] = ...,
) -> Tuple[npt.NDArray[np.float32], OrientResult]: ...
def orient_o3d(pcd: Any, **params: Any) -> OrientResult: ...
def make_scene(
    kind: str = ..., points: int = ..., *, seed: int = ..., noise: float = ...
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
