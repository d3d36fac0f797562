# SPDX-License-Identifier: BSD-3-Clause
"""Globally consistent normal orientation for open scene point clouds (DACPO).

Three lines::

    import numpy as np, pcl_dacpo
    normals, result = pcl_dacpo.orient(points)        # points: (N, 3) array
    print(result.stats["num_blocks"], result.seconds)

``orient`` estimates PCA normals when none are given, orients them (the DACPO
method: blocks, dipole propagation, iterative Poisson, visible connected
regions, a 0-1 program) and returns unit normals facing the free space the
scan was seen from. Built on pcl_dacpo's C core, not on PCL.
"""
import difflib as _difflib

import numpy as _np

from . import _core

__all__ = ["orient", "orient_o3d", "make_scene", "DacpoError", "OrientResult", "default_params"]
__version__ = _core.version

_EDGE_WEIGHTS = {"dipole": 0, "vcr": 1, "overlap": 2}
_DISCONNECTED = {"separate": 0, "error": 1, "bridge": 2, "viewpoint": 3}
_SIGN = {"free_space": 0, "viewpoint": 1, "keep": 2}
_SCAN = {"auto": 0, "single_view": 1, "multi_view": 2}
_ENUMS = {"edge_weight": _EDGE_WEIGHTS, "disconnected": _DISCONNECTED, "sign_policy": _SIGN,
          "scan_kind": _SCAN}
_ALIASES = {"threads": "num_threads"}


class DacpoError(RuntimeError):
    """A failure of the C core: ``status`` (int), ``status_name`` and ``message``."""

    def __init__(self, status, status_name, message):
        super().__init__(f"{status_name}: {message}")
        self.status = status
        self.status_name = status_name
        self.message = message


class OrientResult:
    """What one ``orient`` call found besides the normals.

    Attributes: ``stats`` (dict: points, blocks, edges, components, flips, sign
    policy outcome, ``stage_seconds``, and the work of stages 2-3:
    ``dipole_restarts_total``, ``ipsr_iterations_total``, ...), ``component_labels`` and
    ``block_labels`` (int32 per point, input order), ``block_flips`` (uint8 per
    block), ``confidence`` (float32 per point in [0, 1]: how sure the sign is),
    ``seconds`` (the core's wall time).
    """

    def __init__(self, raw):
        self.stats = raw["stats"]
        self.component_labels = raw["component_labels"]
        self.block_labels = raw["block_labels"]
        self.block_flips = raw["block_flips"]
        self.confidence = raw["confidence"]
        self.seconds = self.stats["total_seconds"]

    def __repr__(self):
        s = self.stats
        return (f"OrientResult(points={s['input_points']}, blocks={s['num_blocks']}, "
                f"components={s['num_components']}, flipped_blocks={s['flipped_blocks']}, "
                f"seconds={self.seconds:.3f})")


def default_params():
    """Every parameter ``orient`` takes, with the C core's default."""
    d = dict(_core.default_params())
    names = {v: k for k, v in _EDGE_WEIGHTS.items()}
    d["edge_weight"] = names[d["edge_weight"]]
    d["disconnected"] = {v: k for k, v in _DISCONNECTED.items()}[d["disconnected"]]
    d["sign_policy"] = {v: k for k, v in _SIGN.items()}[d["sign_policy"]]
    d["scan_kind"] = {v: k for k, v in _SCAN.items()}[d["scan_kind"]]
    d["threads"] = d.pop("num_threads")
    return d


def _check_params(params):
    defaults = _core.default_params()
    out = {}
    for name, value in params.items():
        key = _ALIASES.get(name, name)
        if key not in defaults:
            close = _difflib.get_close_matches(name, list(defaults) + list(_ALIASES), n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise TypeError(f"orient() got an unexpected keyword argument '{name}'{hint}")
        default = defaults[key]
        if key in _ENUMS:
            table = _ENUMS[key]
            if isinstance(value, str):
                if value not in table:
                    raise ValueError(f"{name} must be one of {sorted(table)}, got {value!r}")
                value = table[value]
            elif isinstance(value, (int, _np.integer)) and not isinstance(value, bool) \
                    and int(value) in table.values():
                value = int(value)
            else:
                raise ValueError(f"{name} must be one of {sorted(table)}, got {value!r}")
        elif key == "viewpoint":
            try:
                v = tuple(float(x) for x in value)
            except TypeError:
                raise TypeError(f"viewpoint must be three numbers, got {value!r}") from None
            if len(v) != 3 or not all(_np.isfinite(v)):
                raise ValueError(f"viewpoint must be three finite numbers, got {value!r}")
            value = v
        elif isinstance(default, bool):
            if not isinstance(value, (bool, _np.bool_, int, _np.integer)):
                raise TypeError(f"{name} must be a bool, got {type(value).__name__}")
            value = bool(value)
        elif isinstance(default, int):
            if isinstance(value, bool) or not isinstance(value, (int, _np.integer)):
                raise TypeError(f"{name} must be an int, got {type(value).__name__}")
            if value < 0:
                raise ValueError(f"{name} must be >= 0, got {value}")
            value = int(value)
        else:
            if isinstance(value, bool) or not isinstance(value, (int, float, _np.integer,
                                                                 _np.floating)):
                raise TypeError(f"{name} must be a number, got {type(value).__name__}")
            value = float(value)
        out[key] = value
    if "viewpoint" in out and "sign_policy" not in out:
        out["sign_policy"] = _SIGN["viewpoint"]
    message = _core.validate(out)
    if message:
        raise ValueError(message)
    return out


def _as_points(points, name):
    if hasattr(points, "has_normals") and hasattr(points, "points"):
        raise TypeError(f"{name} is an open3d.geometry.PointCloud: use "
                        "pcl_dacpo.orient_o3d(pcd), which orients its normals in place")
    a = _np.asarray(points)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {a.shape}")
    if not (_np.issubdtype(a.dtype, _np.floating) or _np.issubdtype(a.dtype, _np.integer)):
        raise TypeError(f"{name} must hold numbers, got dtype {a.dtype}")
    return a


def _local_frame(a):
    """(centre, scale) that keep the geometry in float32, or None: only for
    clouds far from the origin (georeferenced: offsets > 1e3 x their size) or
    of extreme size; other clouds are passed as they are."""
    finite = a[_np.isfinite(a).all(axis=1)]
    if len(finite) == 0:
        return None
    lo, hi = finite.min(axis=0).astype(_np.float64), finite.max(axis=0).astype(_np.float64)
    side = float((hi - lo).max())
    centre = 0.5 * lo + 0.5 * hi
    if not (side > 0.0) or not _np.isfinite(side):
        return None
    if _np.abs(centre).max() > 1e3 * side or side > 1e6 or side < 1e-6:
        return centre, side
    return None


def orient(points, normals=None, *, progress=None, **params):
    """Orient the normals of ``points`` consistently; returns ``(normals, result)``.

    points:   (N, 3) array-like of float32/float64 (C- or F-ordered, or lists).
    normals:  optional (N, 3) normal axes to orient (e.g. from Open3D); when
              None, PCA normals are estimated (``normal_k`` neighbours).
    progress: optional ``callable(stage_name, fraction) -> bool``; returning
              False cancels (``DacpoError`` with status ``cancelled``). Ctrl-C
              cancels too (KeyboardInterrupt).
    params:   any ``dacpo_params`` field with the C default (``default_params()``
              lists them): ``k=10``, ``seed=1``, ``threads=0`` (all cores),
              ``num_blocks=0`` (automatic), ``dipole_c=-1`` (by the scan kind),
              ``edge_weight='vcr'``, ``sign_policy='free_space'``,
              ``scan_kind='auto'`` (or ``'single_view'``, ``'multi_view'``),
              ``viewpoint=(x, y, z)`` (then normals face it), ...

    Returns an (N, 3) float32 array of unit normals in the input order and an
    ``OrientResult``; rows whose point has a NaN or inf coordinate get NaN
    normals (labels -1, confidence NaN), as in the PCL class and the CLI. Unknown parameters raise TypeError, bad values
    ValueError, failures of the core ``DacpoError``. The GIL is released while
    the core runs.
    """
    checked = _check_params(params)
    a = _as_points(points, "points")
    given = None
    if normals is not None:
        given = _as_points(normals, "normals")
        if given.shape != a.shape:
            raise ValueError(f"normals must have the shape of points {a.shape}, got {given.shape}")
    frame = _local_frame(a)
    if frame is not None:
        centre, scale = frame
        a = (a.astype(_np.float64) - centre) / scale
        if "viewpoint" in checked:
            checked["viewpoint"] = tuple((_np.asarray(checked["viewpoint"]) - centre) / scale)
    if progress is not None and not callable(progress):
        raise TypeError("progress must be callable(stage_name, fraction) -> bool")
    # rows with a NaN or inf coordinate get NaN normals and labels -1, as in
    # the PCL class and the CLI; the rest is oriented without them
    keep = _np.isfinite(a).all(axis=1)
    dropped = not keep.all()
    if dropped:
        a = a[keep]
        given = given[keep] if given is not None else None
    raw = _core.orient(a, given, checked, progress)
    if raw["status"] != 0:
        raise DacpoError(raw["status"], raw["status_name"], raw["message"])
    if dropped:
        raw = _restore_rows(raw, keep)
    return raw["normals"], OrientResult(raw)


def _restore_rows(raw, keep):
    """The per-point outputs of a run on points[keep], back on every row."""
    out = dict(raw)
    for key, fill in (("normals", _np.nan), ("confidence", _np.nan),
                      ("component_labels", -1), ("block_labels", -1)):
        v = _np.asarray(raw[key])
        full = _np.full((len(keep),) + v.shape[1:], fill, dtype=v.dtype)
        full[keep] = v
        out[key] = full
    return out


def orient_o3d(pcd, **params):
    """Orient an ``open3d.geometry.PointCloud`` in place (its normals, estimated
    first when it has none) and return the ``OrientResult``. Open3D is only
    needed for this function."""
    pts = _np.asarray(pcd.points)
    given = _np.asarray(pcd.normals) if pcd.has_normals() else None
    normals, result = orient(pts, given, **params)
    import open3d  # noqa: F401  (only when called)
    pcd.normals = open3d.utility.Vector3dVector(normals.astype(_np.float64))
    return result


def make_scene(kind="room", points=100000, *, seed=1, noise=0.0):
    """A generated scene with analytic ground-truth normals, as ``(points,
    normals)`` float32 arrays. Kinds: room, plane, sphere, two_rooms, board,
    half_cylinder, s_sheet, box (an open box room)."""
    return _core.make_scene(str(kind), int(points), int(seed), float(noise))
