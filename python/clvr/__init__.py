"""clvr: render unstructured volume meshes held in memory (issue 18).

A thin ctypes layer over libclvr's C API (clvr.h); no compiled extension.

    import clvr, meshio
    mesh = clvr.Mesh.from_meshio(meshio.read("fire.vtu"))
    r = clvr.Renderer(mesh, device="pocl", width=512, height=512)
    img = r.render(spp=64, camera={"azimuth": 30}, tf={"colormap": "viridis"})
    clvr.save_image("fire.png", img)          # the clvr program's writers

Images are numpy float32 arrays of shape (height, width, 4): linear r, g, b
(the background seen through the volume included) and a = opacity along the
ray, rows top to bottom.

Arrays are checked here before any device work (dtype, shape, index range,
NaN); nothing the caller passes is ever modified. Mesh.from_arrays borrows
(CLVR_BORROW) each array that is already C-contiguous with the dtype libclvr
reads (float32 points and fields, uint32 cells): no copy, so keep it
unchanged while the Mesh or a Renderer of it lives (copy=True copies
everything); other arrays are converted and the conversion is kept. Failures raise clvr.Error (or its subclass
clvr.InputError, also a ValueError, for bad arguments and data) carrying
clvr's one-line message.

Besides rendering (API 1.2): setting_names / setting_name / setting_index
(the names a setting takes: "method", "estimator", "sampler", "tonemap",
"element_boxes"), default_size, frame_box (the automatic framing of a box,
without a Renderer), tf_file_window (a transfer function file's own scalar
window) and time series: is_series(path) and Series(path) (its steps'
mesh paths and times, and bounds over all steps).

libclvr is found, in this order: $CLVR_LIBRARY; next to this package (pip
install); the path recorded by the build tree or `cmake --install`
(_config.py); the system's loader (libclvr.so.1).
"""
import ctypes
import math
import os
import warnings

import numpy as np

__all__ = ["Error", "InputError", "Context", "Mesh", "Scene", "Renderer", "save_image", "list_devices",
           "api_version", "version", "CELL_TYPES", "setting_name", "setting_index", "setting_names",
           "default_size", "frame_box", "tf_file_window", "is_series", "Series"]

API_VERSION_MAJOR = 1

# --------------------------------------------------------------------------- library


def _find_library():
    here = os.path.dirname(os.path.abspath(__file__))
    names = ["libclvr.so.%d" % API_VERSION_MAJOR, "libclvr.so"]
    candidates = []
    env = os.environ.get("CLVR_LIBRARY")
    if env:
        candidates.append(env)
    candidates += [os.path.join(here, n) for n in names]
    try:
        from . import _config  # written by CMake (build tree, install)
        for d in _config.LIBRARY_DIRS:
            d = d if os.path.isabs(d) else os.path.normpath(os.path.join(here, d))
            candidates += [os.path.join(d, n) for n in names]
    except ImportError:
        pass
    errors = []
    for c in candidates:
        if os.path.exists(c):
            try:
                return ctypes.CDLL(c)
            except OSError as e:
                errors.append(str(e))
    for n in names:  # the system's loader: ldconfig, LD_LIBRARY_PATH
        try:
            return ctypes.CDLL(n)
        except OSError as e:
            errors.append(str(e))
    raise ImportError("clvr: cannot load libclvr (tried %s): %s; build it (cmake --build build) and set "
                      "CLVR_LIBRARY=/path/to/libclvr.so.%d" % (", ".join(candidates) or "no path",
                                                                "; ".join(errors[-2:]), API_VERSION_MAJOR))


_lib = _find_library()

_c_float3 = ctypes.c_float * 3
_P = ctypes.c_void_p
_S = ctypes.c_char_p
_U32 = ctypes.c_uint32
_U64 = ctypes.c_uint64
_F = ctypes.c_float


class _Message(ctypes.Structure):
    _fields_ = [("result", ctypes.c_int), ("text", ctypes.c_char * 1024)]


_M = ctypes.POINTER(_Message)


class _LoadSettings(ctypes.Structure):
    _fields_ = [("size", _U32), ("field", _S), ("cell_flat", ctypes.c_int), ("field_ranges", ctypes.c_int)]


class _DatasetField(ctypes.Structure):
    _fields_ = [("size", _U32), ("name", ctypes.c_char * 64), ("is_cell", ctypes.c_int), ("components", _U32),
                ("has_range", ctypes.c_int), ("min", _F), ("max", _F), ("loaded", ctypes.c_int)]


class _PreprocessSettings(ctypes.Structure):
    _fields_ = [("size", _U32), ("leaf_size", _U32), ("sampling_size", _U32), ("partitions", _U32),
                ("consume", ctypes.c_int), ("name", _S), ("width", _U32), ("height", _U32),
                ("element_boxes", ctypes.c_int), ("one_curve", ctypes.c_int)]


class _SceneStats(ctypes.Structure):
    _fields_ = [("size", _U32), ("elements", _U64), ("points", _U64), ("instances", _U64), ("instances16", _U64),
                ("leaves", _U64), ("sampling_clusters", _U64), ("leaf_size", _U32), ("sampling_size", _U32),
                ("partitions", _U32), ("lo", _F * 3), ("hi", _F * 3), ("bytes_points_before", _U64),
                ("bytes_points_after", _U64), ("bytes_indices_before", _U64), ("bytes_indices_after", _U64),
                ("bytes_bvh", _U64), ("bytes_bvh_one_per_leaf", _U64), ("bytes_sampling", _U64),
                ("bytes_element_boxes", _U64), ("device_bytes", _U64), ("preprocess_s", ctypes.c_double),
                ("num_stages", _U32), ("stage_name", (ctypes.c_char * 16) * 16), ("stage_s", ctypes.c_double * 16),
                ("scalar_min", _F), ("scalar_max", _F), ("bytes_entry_grids", _U64), ("collapsed_cells", _U64 * 4)]


class _TracerSettings(ctypes.Structure):
    _fields_ = [("size", _U32), ("method", ctypes.c_char * 16), ("estimator", ctypes.c_char * 16),
                ("sampler", ctypes.c_char * 16), ("seed", _U64), ("urm_steps", _U32), ("step", _F), ("bins", _U32),
                ("segments", _U32), ("macrocells", _U32), ("light_dir", _F * 3), ("light_intensity", _F),
                ("ambient", _F), ("shadows", ctypes.c_int), ("background", _F * 3), ("clip_box", ctypes.c_int),
                ("clip_lo", _F * 3), ("clip_hi", _F * 3), ("num_clip_planes", _U32), ("clip_planes", (_F * 4) * 6)]


_PROTOS = {
    "clvr_api_version": (ctypes.c_uint, []),
    "clvr_version_string": (_S, []),
    "clvr_result_name": (_S, [ctypes.c_int]),
    "clvr_list_devices": (ctypes.c_int, [ctypes.c_char_p, ctypes.c_size_t, _M]),
    "clvr_context_create": (ctypes.c_int, [_S, ctypes.POINTER(_P), _M]),
    "clvr_context_destroy": (None, [_P]),
    "clvr_context_describe": (ctypes.c_int, [_P, ctypes.c_char_p, ctypes.c_size_t, ctypes.c_char_p,
                                             ctypes.c_size_t, _M]),
    "clvr_dataset_create": (ctypes.c_int, [_U64, _P, ctypes.c_int, ctypes.POINTER(_P), _M]),
    "clvr_dataset_add_cells": (ctypes.c_int, [_P, _S, _U64, _P, ctypes.c_int, _M]),
    "clvr_dataset_add_field": (ctypes.c_int, [_P, _S, _P, ctypes.c_int, _M]),
    "clvr_dataset_load": (ctypes.c_int, [_S, _S, ctypes.POINTER(_P), _M]),
    "clvr_dataset_load_with": (ctypes.c_int, [_S, ctypes.POINTER(_LoadSettings), ctypes.POINTER(_P), _M]),
    "clvr_dataset_get_field": (ctypes.c_int, [_P, _U32, ctypes.POINTER(_DatasetField), _M]),
    "clvr_dataset_get_array": (ctypes.c_int, [_P, _S, ctypes.POINTER(_P), ctypes.POINTER(ctypes.c_int), _M]),
    "clvr_scene_create": (ctypes.c_int, [_P, _P, _S, ctypes.POINTER(_PreprocessSettings), ctypes.POINTER(_P), _M]),
    "clvr_scene_destroy": (None, [_P]),
    "clvr_scene_get_stats": (ctypes.c_int, [_P, ctypes.POINTER(_SceneStats), _M]),
    "clvr_tracer_create_on": (ctypes.c_int, [_P, ctypes.POINTER(_TracerSettings), _U32, _U32, ctypes.POINTER(_P),
                                             _M]),
    "clvr_tracer_settings_init": (None, [ctypes.POINTER(_TracerSettings)]),
    "clvr_tracer_get_settings": (ctypes.c_int, [_P, ctypes.POINTER(_TracerSettings), _M]),
    "clvr_tracer_set_settings": (ctypes.c_int, [_P, ctypes.POINTER(_TracerSettings), _M]),
    "clvr_dataset_destroy": (None, [_P]),
    "clvr_dataset_counts": (ctypes.c_int, [_P, ctypes.POINTER(_U64), ctypes.POINTER(_U64),
                                           ctypes.POINTER(_U32), _M]),
    "clvr_dataset_field_name": (ctypes.c_int, [_P, _U32, ctypes.c_char_p, ctypes.c_size_t, _M]),
    "clvr_dataset_bounds": (ctypes.c_int, [_P, _c_float3, _c_float3, _M]),
    "clvr_dataset_field_range": (ctypes.c_int, [_P, _S, ctypes.POINTER(_F), ctypes.POINTER(_F), _M]),
    "clvr_tracer_create": (ctypes.c_int, [_P, _P, _S, _U32, _U32, ctypes.POINTER(_P), _M]),
    "clvr_tracer_destroy": (None, [_P]),
    "clvr_tracer_set_camera": (ctypes.c_int, [_P, _c_float3, _c_float3, _c_float3, _F, _M]),
    "clvr_tracer_frame": (ctypes.c_int, [_P, _P, _F, _F, _F, _F, _M]),
    "clvr_tracer_get_camera": (ctypes.c_int, [_P, _c_float3, _c_float3, _c_float3, _M]),
    "clvr_tracer_set_tf": (ctypes.c_int, [_P, _S, _S, _F, _F, _F, ctypes.c_int, _M]),
    "clvr_tracer_set_tf_table": (ctypes.c_int, [_P, _P, _U32, _F, _F, _F, _M]),
    "clvr_tracer_set_light": (ctypes.c_int, [_P, _c_float3, _F, _F, ctypes.c_int, _M]),
    "clvr_tracer_set_background": (ctypes.c_int, [_P, _c_float3, _M]),
    "clvr_tracer_set_method": (ctypes.c_int, [_P, _S, _S, _M]),
    "clvr_tracer_set_seed": (ctypes.c_int, [_P, _U64, _M]),
    "clvr_tracer_render": (ctypes.c_int, [_P, _U32, _M]),
    "clvr_tracer_size": (ctypes.c_int, [_P, ctypes.POINTER(_U32), ctypes.POINTER(_U32), _M]),
    "clvr_tracer_read_image": (ctypes.c_int, [_P, _P, ctypes.c_size_t, _M]),
    "clvr_tracer_stat": (ctypes.c_int, [_P, _S, ctypes.POINTER(ctypes.c_double), _M]),
    "clvr_image_save": (ctypes.c_int, [_S, _U32, _U32, _P, _F, _S, ctypes.c_int, _M]),
    # API 1.2
    "clvr_setting_name": (_S, [_S, _U32]),
    "clvr_setting_index": (ctypes.c_int, [_S, _S, ctypes.POINTER(_U32), _M]),
    "clvr_tracer_set_pixel_filter": (ctypes.c_int, [_P, _S, _M]),  # API 1.3
    "clvr_tracer_pixel_filter": (_S, [_P]),
    "clvr_tracer_set_denoise": (ctypes.c_int, [_P, ctypes.c_int, _M]),  # API 1.4
    "clvr_tracer_denoise": (ctypes.c_int, [_P]),
    "clvr_tracer_read_denoised": (ctypes.c_int, [_P, _P, ctypes.c_size_t, _M]),
    "clvr_tracer_set_adaptive": (ctypes.c_int, [_P, ctypes.c_float, _M]),  # API 1.7
    "clvr_tracer_adaptive": (ctypes.c_float, [_P]),
    "clvr_default_size": (None, [ctypes.POINTER(_U32), ctypes.POINTER(_U32)]),
    "clvr_frame_box": (ctypes.c_int, [_c_float3, _c_float3, _P, _F, _F, _F, _F, _U32, _U32, _c_float3, _c_float3,
                                      _M]),
    "clvr_tf_file_window": (ctypes.c_int, [_S, ctypes.POINTER(ctypes.c_int), ctypes.POINTER(_F),
                                           ctypes.POINTER(_F), _M]),
    "clvr_path_is_series": (ctypes.c_int, [_S]),
    "clvr_series_open": (ctypes.c_int, [_S, ctypes.POINTER(_P), _M]),
    "clvr_series_destroy": (None, [_P]),
    "clvr_series_count": (_U32, [_P]),
    "clvr_series_step": (ctypes.c_int, [_P, _U32, ctypes.POINTER(_S), ctypes.POINTER(ctypes.c_double), _M]),
    "clvr_series_bounds": (ctypes.c_int, [_P, _S, _c_float3, _c_float3, ctypes.POINTER(_F), ctypes.POINTER(_F),
                                          _M]),
}
for _name, (_res, _args) in _PROTOS.items():
    _fn = getattr(_lib, _name)
    _fn.restype = _res
    _fn.argtypes = _args

if _lib.clvr_api_version() // 1000 != API_VERSION_MAJOR:
    raise ImportError("clvr: libclvr has API version %d.%d; this module needs %d.x"
                      % (_lib.clvr_api_version() // 1000, _lib.clvr_api_version() % 1000, API_VERSION_MAJOR))

_COPY = 0
_BORROW = 1
_INPUT_RESULTS = {"ERR_USAGE", "ERR_BAD_INDEX", "ERR_BAD_VALUE", "ERR_BAD_FIELD", "ERR_EMPTY", "ERR_OVERFLOW"}


class Error(Exception):
    """A libclvr failure: str(e) is clvr's one-line message, e.result its
    name ("ERR_NO_DEVICE", ...)."""

    def __init__(self, message, result="ERR_INTERNAL"):
        super().__init__(message)
        self.result = result


class InputError(Error, ValueError):
    """A bad argument or bad data (shape, dtype, index, NaN, unknown name)."""

    def __init__(self, message, result="ERR_USAGE"):
        super().__init__(message, result)


def _call(fn, *args):
    msg = _Message()
    rc = fn(*args, ctypes.byref(msg))
    if rc != 0:
        name = _lib.clvr_result_name(rc).decode()
        text = msg.text.decode("utf-8", "replace")
        raise (InputError if name in _INPUT_RESULTS else Error)(text, name)


def _b(s):
    return None if s is None else os.fsencode(s) if isinstance(s, os.PathLike) else str(s).encode()


def _text(what, v):
    if not isinstance(v, str):
        raise InputError("%s must be a string, got %r" % (what, v))
    return v.encode()


def _count(what, v, lo=0, hi=0xFFFFFFFF):
    """v as an int in [lo, hi] (hi: the C field's largest value, so that
    ctypes never wraps it silently); bools are not counts."""
    if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or not lo <= v <= hi:
        if hi == 0xFFFFFFFF:
            raise InputError("%s must be a whole number >= %d, got %r" % (what, lo, v))
        raise InputError("%s must be a whole number in [%d, %d], got %r" % (what, lo, hi, v))
    return int(v)


def api_version():
    """libclvr's CLVR_API_VERSION (major * 1000 + minor)."""
    return _lib.clvr_api_version()


def version():
    """The clvr release, e.g. "0.1.0"."""
    return _lib.clvr_version_string().decode()


def list_devices():
    """The OpenCL platforms and devices, as text."""
    buf = ctypes.create_string_buffer(1 << 16)
    _call(_lib.clvr_list_devices, buf, len(buf))
    return buf.value.decode("utf-8", "replace")


# --------------------------------------------------------------------------- arrays

# clvr's cell types under their meshio / VTK names, with vertex counts and VTK ids.
CELL_TYPES = {"tetra": (4, 10), "pyramid": (5, 14), "wedge": (6, 13), "hexahedron": (8, 12)}
_VTK_IDS = {v[1]: k for k, v in CELL_TYPES.items()}


def _as_points(points):
    a = np.asarray(points)
    if a.dtype.kind not in "fiu":
        raise InputError("points has dtype %s; give real numbers (float32 is used)" % a.dtype)
    if a.ndim != 2 or a.shape[1] != 3 or a.shape[0] < 1:
        raise InputError("points has shape %s; it must be (N, 3) with N >= 1" % (a.shape,))
    with np.errstate(over="ignore", invalid="ignore"):
        p = np.ascontiguousarray(a, dtype=np.float32)
    bad = ~np.isfinite(p)
    if bad.any():
        i, k = np.argwhere(bad)[0]
        raise InputError("points[%d, %d] is %r; coordinates must be finite (and fit in float32)"
                         % (i, k, a[i, k].item()), "ERR_BAD_VALUE")
    return p


def _as_cells(name, cells, num_points):
    if name not in CELL_TYPES:
        raise InputError("cells[%r]: unknown cell type; clvr renders %s" % (name, ", ".join(CELL_TYPES)))
    nv = CELL_TYPES[name][0]
    a = np.asarray(cells)
    if a.dtype.kind not in "iu":
        raise InputError("cells[%r] has dtype %s; indices must be integers" % (name, a.dtype))
    if a.size == 0:
        return np.zeros((0, nv), np.uint32)
    if a.ndim != 2 or a.shape[1] != nv:
        raise InputError("cells[%r] has shape %s; it must be (M, %d)" % (name, a.shape, nv))
    bad = (a < 0) | (a >= num_points)
    if bad.any():
        i, k = np.argwhere(bad)[0]
        raise InputError("cells[%r][%d, %d] is %d but there are %d points (indices run from 0 to %d)"
                         % (name, i, k, a[i, k], num_points, num_points - 1), "ERR_BAD_INDEX")
    return np.ascontiguousarray(a, dtype=np.uint32)


def _as_field(name, values, num_points):
    if not isinstance(name, str) or not name:
        raise InputError("point_data key %r: field names are non-empty strings" % (name,))
    a = np.asarray(values)
    if a.dtype.kind not in "fiu":
        raise InputError("point_data[%r] has dtype %s; give real numbers" % (name, a.dtype))
    if a.ndim == 2 and a.shape[1] == 1:
        a = a[:, 0]
    if a.ndim != 1 or a.shape[0] != num_points:
        raise InputError("point_data[%r] has shape %s; it must be (%d,): one scalar per point"
                         % (name, a.shape, num_points))
    with np.errstate(over="ignore", invalid="ignore"):
        f = np.ascontiguousarray(a, dtype=np.float32)
    bad = ~np.isfinite(f)
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError("point_data[%r][%d] is %r; values must be finite (and fit in float32)"
                         % (name, i, a[i].item()), "ERR_BAD_VALUE")
    return f


def _ptr(a):
    return a.ctypes.data_as(ctypes.c_void_p)


# --------------------------------------------------------------------------- objects


class _Handle:
    """An object that owns one libclvr handle (self._h), released by its
    class's _destroy (bound as a class attribute: module globals may be gone
    when __del__ runs at exit), by close(), or at the end of a with block."""

    def close(self):
        """Releases the handle now (also done when the object goes away)."""
        if getattr(self, "_h", None) and self._h.value:
            self._destroy(self._h)
            self._h = _P()

    def __del__(self):
        self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Context(_Handle):
    """An OpenCL device: "pocl", "cpu", "gpu", "P:D" or part of a name
    (None: the first GPU, else PoCL). Renderers may share one."""

    def __init__(self, device=None):
        self._h = _P()
        _call(_lib.clvr_context_create, _b(device), ctypes.byref(self._h))
        dev, plat = ctypes.create_string_buffer(256), ctypes.create_string_buffer(256)
        _call(_lib.clvr_context_describe, self._h, dev, 256, plat, 256)
        self.device_name = dev.value.decode("utf-8", "replace")
        self.platform_name = plat.value.decode("utf-8", "replace")
        self._renderers = 0

    _destroy = staticmethod(_lib.clvr_context_destroy)

    def __repr__(self):
        return "clvr.Context(%r on %r)" % (self.device_name, self.platform_name)


class Mesh(_Handle):
    """An unstructured mesh on the host: points, cells of the four types and
    named scalars per point. Build it with from_arrays, from_meshio,
    from_vtk or load. Ownership is stated per constructor: from_arrays
    lends libclvr the caller's arrays when their layout allows (see there),
    load gives libclvr the file's data."""

    def __init__(self, _handle):
        self._h = _handle
        self._keep = []

    @classmethod
    def from_arrays(cls, points, cells, point_data=None, copy=False):
        """points (N, 3) reals; cells {"tetra": (M, 4), "pyramid": (M, 5),
        "wedge": (M, 6), "hexahedron": (M, 8)} integer arrays (VTK vertex
        order); point_data {name: (N,) reals}. Everything is checked first
        (InputError names the array, the position and the fix); nothing is
        modified.

        Ownership, per array: one that is already C-contiguous with
        libclvr's dtype (points and point_data float32, cells uint32) is
        borrowed, not copied (CLVR_BORROW; Mesh.borrowed(name) says which):
        it must stay unchanged while this Mesh or a Renderer made from it
        lives (changes made meanwhile are seen by later renders). Any other
        array is converted once and the converted copy is lent instead.
        copy=True: libclvr copies every array (CLVR_COPY) and keeps none of
        the caller's."""
        keep = []
        p = _as_points(points)
        n = p.shape[0]
        if isinstance(cells, (list, tuple)):  # meshio's [(type, array), ...]
            merged = {}
            for item in cells:
                if not (isinstance(item, (list, tuple)) and len(item) == 2):
                    raise InputError("cells as a list must hold (type, array) pairs")
                merged.setdefault(item[0], []).append(np.asarray(item[1]))
            cells = {k: np.concatenate(v) if len(v) > 1 else v[0] for k, v in merged.items()}
        if not isinstance(cells, dict):
            raise InputError("cells must be a dict like {'tetra': (M, 4) array}; got %s" % type(cells).__name__)
        cs = {name: _as_cells(name, c, n) for name, c in cells.items()}
        if not any(c.shape[0] for c in cs.values()):
            raise InputError("the mesh has no cells: give at least one of %s" % ", ".join(CELL_TYPES), "ERR_EMPTY")
        point_data = point_data or {}
        if not isinstance(point_data, dict):
            raise InputError("point_data must be a dict {name: (N,) array}")
        fs = {name: _as_field(name, v, n) for name, v in point_data.items()}
        if not fs:
            raise InputError("point_data is empty: clvr renders a scalar per point; give one")
        own = _COPY if copy else _BORROW
        h = _P()
        _call(_lib.clvr_dataset_create, n, _ptr(p), own, ctypes.byref(h))
        mesh = cls(h)
        # Lent arrays live as long as this object (a Renderer keeps the Mesh).
        mesh._keep = [] if copy else [p] + list(cs.values()) + list(fs.values())
        for name, c in cs.items():
            if c.shape[0]:
                _call(_lib.clvr_dataset_add_cells, h, name.encode(), c.shape[0], _ptr(c), own)
        for name, f in fs.items():
            _call(_lib.clvr_dataset_add_field, h, name.encode(), _ptr(f), own)
        return mesh

    @classmethod
    def from_meshio(cls, m, fields=None):
        """A meshio.Mesh: its tetra, pyramid, wedge and hexahedron blocks
        (other cell types are left out with a warning) and its scalar point
        data (vector arrays are left out), or only `fields` (names).
        Through from_arrays: arrays already in libclvr's layout (float32
        points or fields) are lent, not copied; meshio's usual float64
        points and int64 cells are converted."""
        cells, skipped = {}, {}
        for block in m.cells:
            if block.type in CELL_TYPES:
                cells.setdefault(block.type, []).append(np.asarray(block.data))
            else:
                skipped[block.type] = skipped.get(block.type, 0) + len(block.data)
        if skipped:
            warnings.warn("clvr: left out %s; clvr renders %s" % (
                ", ".join("%d %s" % (v, k) for k, v in skipped.items()), ", ".join(CELL_TYPES)))
        cells = {k: np.concatenate(v) if len(v) > 1 else v[0] for k, v in cells.items()}
        return cls.from_arrays(m.points, cells, _scalars(m.point_data, fields))

    @classmethod
    def from_vtk(cls, ugrid, fields=None):
        """A vtkUnstructuredGrid (python3-vtk9), as from_meshio: float32
        points and point arrays are lent from VTK's memory (the numpy views
        keep the VTK arrays alive), cells are gathered into new arrays."""
        from vtkmodules.util.numpy_support import vtk_to_numpy
        if ugrid.GetPoints() is None:
            raise InputError("the vtkUnstructuredGrid has no points")
        points = vtk_to_numpy(ugrid.GetPoints().GetData())
        types = vtk_to_numpy(ugrid.GetCellTypesArray()) if ugrid.GetNumberOfCells() else np.zeros(0, np.uint8)
        ca = ugrid.GetCells()
        conn = vtk_to_numpy(ca.GetConnectivityArray())
        offs = vtk_to_numpy(ca.GetOffsetsArray())
        cells, skipped = {}, 0
        for vid in np.unique(types):
            sel = np.nonzero(types == vid)[0]
            name = _VTK_IDS.get(int(vid))
            if name is None:
                skipped += len(sel)
                continue
            nv = CELL_TYPES[name][0]
            if not np.all(offs[sel + 1] - offs[sel] == nv):
                raise InputError("VTK cells of type %d (%s) with a vertex count other than %d" % (vid, name, nv))
            cells[name] = conn[offs[sel][:, None] + np.arange(nv)[None, :]]
        if skipped:
            warnings.warn("clvr: left out %d cells of other types; clvr renders %s" % (skipped, ", ".join(CELL_TYPES)))
        pd = ugrid.GetPointData()
        data = {}
        for i in range(pd.GetNumberOfArrays()):
            arr = pd.GetArray(i)
            if arr is not None and arr.GetName():
                data[arr.GetName()] = vtk_to_numpy(arr)
        return cls.from_arrays(points, cells, _scalars(data, fields))

    @classmethod
    def load(cls, path, scalar=None, cell_flat=False, field_ranges=False, field=None):
        """A mesh file: clvr .bin, .umesh and legacy .vtk through libclvr's
        readers (the mesh owns what it read: nothing is borrowed); anything
        else (.vtu, .msh, ...) through meshio (see from_meshio).

        scalar: the field rendered by default, as the program's --scalar:
        "NAME", "point:NAME", "cell:NAME" or a component "NAME:x" /
        "NAME:0" (a vector named plainly: its magnitude; None: the file's first). Every field of the file is
        listed by `fields`, and Renderer(mesh, field=NAME) renders another
        one (read from the file then). cell_flat: show cell data flat (each
        element its own value) instead of averaged to the points.
        field_ranges: decode every field now for its range (`fields`,
        field_range); else only the fields read. field is the old name of
        scalar."""
        if scalar is None:
            scalar = field
        ext = os.path.splitext(os.fspath(path))[1].lower()
        if ext in (".bin", ".umesh", ".vtk"):
            ls = _LoadSettings(ctypes.sizeof(_LoadSettings), _b(scalar), 1 if cell_flat else 0,
                               1 if field_ranges else 0)
            h = _P()
            _call(_lib.clvr_dataset_load_with, _b(os.fspath(path)), ctypes.byref(ls), ctypes.byref(h))
            return cls(h)
        import meshio
        m = meshio.read(os.fspath(path))
        if scalar is None:
            return cls.from_meshio(m)
        # The chosen scalar first (the default one), then the others.
        data = _scalars(m.point_data, None)
        if scalar not in data:
            raise InputError("%s: no scalar point field %r; it has %s" % (path, scalar, sorted(data) or "none"),
                             "ERR_BAD_FIELD")
        names = [scalar] + [k for k in data if k != scalar]
        return cls.from_meshio(m, names)

    _destroy = staticmethod(_lib.clvr_dataset_destroy)

    def close(self):
        """Releases the mesh (a Renderer made from it keeps libclvr's copy alive)."""
        super().close()

    def _counts(self):
        n, nf = _U64(), _U32()
        nc = (_U64 * 4)()
        _call(_lib.clvr_dataset_counts, self._h, ctypes.byref(n), nc, ctypes.byref(nf))
        return n.value, list(nc), nf.value

    @property
    def num_points(self):
        return self._counts()[0]

    @property
    def num_cells(self):
        """{"tetra": count, ...} (every type, zero included)."""
        return dict(zip(CELL_TYPES, self._counts()[1]))

    @property
    def field_names(self):
        names = []
        for i in range(self._counts()[2]):
            buf = ctypes.create_string_buffer(64)
            _call(_lib.clvr_dataset_field_name, self._h, i, buf, 64)
            names.append(buf.value.decode())
        return names

    @property
    def fields(self):
        """Every field, in order: a file's arrays as the file has them (also
        those not read yet), or the point_data given. A list of dicts:
        name, association ("point" or "cell"), components, range ((lo, hi),
        or None when not decoded yet), loaded (in memory now)."""
        out = []
        for i in range(self._counts()[2]):
            f = _DatasetField()
            f.size = ctypes.sizeof(_DatasetField)
            _call(_lib.clvr_dataset_get_field, self._h, i, ctypes.byref(f))
            out.append({"name": f.name.decode("utf-8", "replace"), "association": "cell" if f.is_cell else "point",
                        "components": f.components, "range": (f.min, f.max) if f.has_range else None,
                        "loaded": bool(f.loaded)})
        return out

    def borrowed(self, name):
        """True when libclvr reads the caller's own array for `name`
        ("points", a cell type or a field name), without a copy."""
        data, b = _P(), ctypes.c_int()
        _call(_lib.clvr_dataset_get_array, self._h, _b(name), ctypes.byref(data), ctypes.byref(b))
        return bool(b.value)

    def array_address(self, name):
        """The address of the array libclvr reads for `name` (compare with
        a numpy array's .ctypes.data to see that it was borrowed)."""
        data, b = _P(), ctypes.c_int()
        _call(_lib.clvr_dataset_get_array, self._h, _b(name), ctypes.byref(data), ctypes.byref(b))
        return data.value or 0

    @property
    def bounds(self):
        """((xmin, ymin, zmin), (xmax, ymax, zmax))."""
        lo, hi = _c_float3(), _c_float3()
        _call(_lib.clvr_dataset_bounds, self._h, lo, hi)
        return tuple(lo), tuple(hi)

    def field_range(self, field=None):
        lo, hi = _F(), _F()
        _call(_lib.clvr_dataset_field_range, self._h, _b(field), ctypes.byref(lo), ctypes.byref(hi))
        return lo.value, hi.value

    def __repr__(self):
        n, nc, _ = self._counts()
        return "clvr.Mesh(%d points, %s, fields %s)" % (
            n, ", ".join("%d %s" % (c, t) for t, c in zip(CELL_TYPES, nc) if c), self.field_names)


def _scalars(data, fields):
    out = {}
    for name, v in data.items():
        a = np.asarray(v)
        if fields is not None and name not in fields:
            continue
        if a.ndim == 1 or (a.ndim == 2 and a.shape[1] == 1):
            out[str(name)] = a
    if fields is not None:
        missing = [f for f in fields if f not in out]
        if missing:
            raise InputError("no scalar point field %s; the mesh has %s" % (missing, sorted(out) or "none"),
                             "ERR_BAD_FIELD")
    return out


def _vec3(name, v):
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InputError("%s must be 3 finite numbers, got %r" % (name, v))
    return _c_float3(*a)


class Scene(_Handle):
    """A mesh preprocessed on a device (Quick Clusters and the trees), as its
    own, timed step; Renderers made from it share it.

    mesh: a clvr.Mesh; device: a device string (see Context) or a Context;
    field: the scalar (None: the mesh's current one; a file's other field
    by name is read now); leaf_size, sampling_size: elements per leaf and
    per sampling cluster (the paper's 16); partitions: preprocess in that
    many pieces to bound peak memory (0: automatic); one_curve: "auto"
    (default), "on" or "off": a mesh of several cell types on one Hilbert
    curve, every cell stored as a hex with repeated corners (stats'
    collapsed_cells counts them: tets, pyramids, wedges, 0), or one curve
    per type; auto takes one curve when it costs at most 1.5x the index
    slots."""

    def __init__(self, mesh, device="pocl", field=None, leaf_size=16, sampling_size=16, partitions=0,
                 one_curve="auto"):
        if not isinstance(mesh, Mesh):
            raise InputError("mesh must be a clvr.Mesh (Mesh.from_arrays, from_meshio, from_vtk, load)")
        for what, v in (("leaf_size", leaf_size), ("sampling_size", sampling_size), ("partitions", partitions)):
            _count(what, v)
        self.context = device if isinstance(device, Context) else Context(device)
        self.mesh = mesh
        oc = _U32()
        _call(_lib.clvr_setting_index, b"one_curve", _text("one_curve", one_curve), ctypes.byref(oc))
        ps = _PreprocessSettings(ctypes.sizeof(_PreprocessSettings), int(leaf_size), int(sampling_size),
                                 int(partitions), 0, None, 0, 0, 0, int(oc.value))
        self._h = _P()
        _call(_lib.clvr_scene_create, self.context._h, mesh._h, _b(field), ctypes.byref(ps), ctypes.byref(self._h))

    _destroy = staticmethod(_lib.clvr_scene_destroy)

    @property
    def stats(self):
        """The preprocessing's figures: counts, bytes (the paper's Table 1),
        preprocess_s (wall, compilation excluded) and stages {name: s}."""
        st = _SceneStats()
        st.size = ctypes.sizeof(_SceneStats)
        _call(_lib.clvr_scene_get_stats, self._h, ctypes.byref(st))
        out = {k: getattr(st, k) for k, _ in _SceneStats._fields_
               if k not in ("size", "lo", "hi", "num_stages", "stage_name", "stage_s", "collapsed_cells")}
        out["collapsed_cells"] = tuple(st.collapsed_cells)
        out["bounds"] = (tuple(st.lo), tuple(st.hi))
        out["stages"] = {st.stage_name[i].value.decode(): st.stage_s[i] for i in range(st.num_stages)}
        return out


_SETTINGS_STR = ("method", "estimator", "sampler")
_SETTINGS_VEC = ("light_dir", "background", "clip_lo", "clip_hi")


def _settings_dict(ts):
    d = {}
    for k, _ in _TracerSettings._fields_:
        if k == "size":
            continue
        v = getattr(ts, k)
        if k in _SETTINGS_STR:
            v = v.decode()
        elif k in _SETTINGS_VEC:
            v = tuple(v)
        elif k == "clip_planes":
            v = [tuple(v[i]) for i in range(ts.num_clip_planes)]
        elif k in ("shadows", "clip_box"):
            v = bool(v)
        d[k] = v
    del d["num_clip_planes"]
    return d


def _settings_apply(ts, kw):
    names = set(k for k, _ in _TracerSettings._fields_) - {"size", "num_clip_planes"}
    unknown = set(kw) - names
    if unknown:
        raise InputError("unknown setting(s) %s; use %s" % (sorted(unknown), ", ".join(sorted(names))))
    for k, v in kw.items():
        if k in _SETTINGS_STR:
            setattr(ts, k, _text(k, v))
        elif k in _SETTINGS_VEC:
            setattr(ts, k, _vec3(k, v))
        elif k == "clip_planes":
            planes = np.asarray(v, dtype=np.float64).reshape(-1, 4) if len(v) else np.zeros((0, 4))
            if planes.shape[0] > 6:
                raise InputError("clip_planes: at most 6 planes (nx, ny, nz, d)")
            ts.num_clip_planes = planes.shape[0]
            for i, p in enumerate(planes):
                ts.clip_planes[i] = (_F * 4)(*p)
        elif k in ("shadows", "clip_box"):
            setattr(ts, k, 1 if v else 0)
        elif k in ("step", "light_intensity", "ambient"):
            setattr(ts, k, float(v))
        else:
            setattr(ts, k, _count(k, v, 0, 0xFFFFFFFFFFFFFFFF if k == "seed" else 0xFFFFFFFF))
    if "clip_lo" in kw or "clip_hi" in kw:
        ts.clip_box = 1 if kw.get("clip_box", True) else 0


class Renderer(_Handle):
    """The clvr path tracer over one mesh: preprocesses it on the device
    (Quick Clusters) once, then renders progressively.

    mesh: a clvr.Mesh, or a clvr.Scene already preprocessed (then device
    and field come from the scene); device: a device string (see Context)
    or a Context; field: the scalar to render (None: the mesh's current
    one; a file's other field by name: read from the file now); settings:
    any of Renderer.settings' keys (method, estimator, sampler, seed,
    urm_steps, step, bins, segments, macrocells, light_dir,
    light_intensity, ambient, shadows, background, clip_box, clip_lo,
    clip_hi, clip_planes, pixel_filter: "box", the default, antialiased,
    or "point", the ray through each pixel's centre as VTK draws; denoise:
    True keeps the guides that image(denoised=True) needs, off by default;
    adaptive: adaptive sampling's threshold, 0.1 by default, 0 off: each
    frame also gives one more sample to the pixels whose neighbours differ
    the most, the same expected image)."""

    def __init__(self, mesh, device="pocl", width=512, height=512, field=None, **settings):
        if not isinstance(mesh, (Mesh, Scene)):
            raise InputError("mesh must be a clvr.Mesh (Mesh.from_arrays, from_meshio, from_vtk, load) or a "
                             "clvr.Scene")
        for what, v in (("width", width), ("height", height)):
            _count(what, v, 1, 65536)
        settings = dict(settings)
        denoise = settings.pop("denoise", None)
        adaptive = settings.pop("adaptive", None)
        pixel_filter = settings.pop("pixel_filter", None)
        if pixel_filter is not None:
            setting_index("pixel_filter", pixel_filter)  # a bad name fails before any device work
        ts = _TracerSettings()
        _lib.clvr_tracer_settings_init(ctypes.byref(ts))
        _settings_apply(ts, settings)
        self._h = _P()
        if isinstance(mesh, Scene):
            self.scene, self.context, self.mesh = mesh, mesh.context, mesh.mesh
            _call(_lib.clvr_tracer_create_on, mesh._h, ctypes.byref(ts), int(width), int(height),
                  ctypes.byref(self._h))
        else:
            self.context = device if isinstance(device, Context) else Context(device)
            self.mesh = mesh  # keeps the arrays it lent alive
            _call(_lib.clvr_tracer_create, self.context._h, mesh._h, _b(field), int(width), int(height),
                  ctypes.byref(self._h))
            if settings:
                _call(_lib.clvr_tracer_set_settings, self._h, ctypes.byref(ts))
        if pixel_filter is not None:
            _call(_lib.clvr_tracer_set_pixel_filter, self._h, _text("pixel_filter", pixel_filter))
        if denoise is not None:
            _call(_lib.clvr_tracer_set_denoise, self._h, 1 if denoise else 0)
        if adaptive is not None:
            _call(_lib.clvr_tracer_set_adaptive, self._h, float(adaptive))
        self.width, self.height = int(width), int(height)
        self._seed = int(ts.seed)  # the renderer's default, as the program's --seed

    @property
    def settings(self):
        """Every render setting as a dict (see the class docstring)."""
        ts = _TracerSettings()
        ts.size = ctypes.sizeof(_TracerSettings)
        _call(_lib.clvr_tracer_get_settings, self._h, ctypes.byref(ts))
        d = _settings_dict(ts)
        d["pixel_filter"] = _lib.clvr_tracer_pixel_filter(self._h).decode()
        d["denoise"] = bool(_lib.clvr_tracer_denoise(self._h))
        d["adaptive"] = float(_lib.clvr_tracer_adaptive(self._h))
        return d

    def set_settings(self, **kw):
        """Changes the given settings (all checked; all or none applied)."""
        kw = dict(kw)
        denoise = kw.pop("denoise", None)
        adaptive = kw.pop("adaptive", None)
        pixel_filter = kw.pop("pixel_filter", None)
        if pixel_filter is not None:
            setting_index("pixel_filter", pixel_filter)  # checked before anything changes
        ts = _TracerSettings()
        ts.size = ctypes.sizeof(_TracerSettings)
        _call(_lib.clvr_tracer_get_settings, self._h, ctypes.byref(ts))
        _settings_apply(ts, kw)
        _call(_lib.clvr_tracer_set_settings, self._h, ctypes.byref(ts))
        if pixel_filter is not None:
            _call(_lib.clvr_tracer_set_pixel_filter, self._h, _text("pixel_filter", pixel_filter))
        if denoise is not None:
            _call(_lib.clvr_tracer_set_denoise, self._h, 1 if denoise else 0)
        if adaptive is not None:
            _call(_lib.clvr_tracer_set_adaptive, self._h, float(adaptive))
        self._seed = int(ts.seed)

    _destroy = staticmethod(_lib.clvr_tracer_destroy)

    def close(self):
        """Releases the device memory now (also done when the object goes away)."""
        super().close()

    # settings: each restarts the accumulation

    def set_camera(self, camera):
        """camera: {"eye": xyz, "target": xyz, "up": xyz (default +y), "fovy": deg (30)}
        or the automatic framing {"azimuth": deg, "elevation": deg, "zoom": f,
        "up": xyz, "fovy": deg} (all optional: the program's defaults)."""
        if not isinstance(camera, dict):
            raise InputError("camera must be a dict: {'eye', 'target', 'up', 'fovy'} or "
                             "{'azimuth', 'elevation', 'zoom', 'up', 'fovy'}")
        known = {"eye", "target", "up", "fovy", "azimuth", "elevation", "zoom"}
        unknown = set(camera) - known
        if unknown:
            raise InputError("camera: unknown key(s) %s; use %s" % (sorted(unknown), sorted(known)))
        up = camera.get("up", (0, 1, 0))
        fovy = float(camera.get("fovy", 30.0))
        if "eye" in camera or "target" in camera:
            if "eye" not in camera or "target" not in camera:
                raise InputError("camera: give both 'eye' and 'target' (or neither, for the automatic framing)")
            _call(_lib.clvr_tracer_set_camera, self._h, _vec3("camera['eye']", camera["eye"]),
                  _vec3("camera['target']", camera["target"]), _vec3("camera['up']", up), fovy)
        else:
            u = _vec3("camera['up']", up)
            _call(_lib.clvr_tracer_frame, self._h, ctypes.cast(u, _P), float(camera.get("azimuth", 0.0)),
                  float(camera.get("elevation", 0.0)), float(camera.get("zoom", 1.0)), fovy)

    @property
    def camera(self):
        e, t, u = _c_float3(), _c_float3(), _c_float3()
        _call(_lib.clvr_tracer_get_camera, self._h, e, t, u)
        return {"eye": tuple(e), "target": tuple(t), "up": tuple(u)}

    def set_tf(self, tf):
        """tf: a colour-map name; or {"colormap": name, "file": path,
        "range": (lo, hi), "density": d (None: automatic), "ramp": bool};
        or {"table": (n, 4) array of linear r, g, b, opacity in [0, 1],
        "range": (lo, hi), "density": d (default 1)}."""
        if isinstance(tf, str):
            tf = {"colormap": tf}
        if not isinstance(tf, dict):
            raise InputError("tf must be a colour-map name or a dict (see Renderer.set_tf)")
        rng = tf.get("range")
        if rng is not None:
            rng = tuple(float(x) for x in rng)
            if len(rng) != 2:
                raise InputError("tf['range'] must be (lo, hi)")
        if "table" in tf:
            t = np.asarray(tf["table"])
            if t.dtype.kind not in "fiu" or t.ndim != 2 or t.shape[1] != 4 or t.shape[0] < 2:
                raise InputError("tf['table'] must be an (n >= 2, 4) array of reals (r, g, b, opacity); "
                                 "got shape %s dtype %s" % (t.shape, t.dtype))
            t = np.ascontiguousarray(t, dtype=np.float32)
            if rng is None:
                rng = self.mesh.field_range()
            _call(_lib.clvr_tracer_set_tf_table, self._h, _ptr(t), t.shape[0], rng[0], rng[1],
                  float(tf.get("density", 1.0)))
            return
        unknown = set(tf) - {"colormap", "file", "range", "density", "ramp"}
        if unknown:
            raise InputError("tf: unknown key(s) %s; use colormap, file, range, density, ramp (or table)"
                             % sorted(unknown))
        d = tf.get("density")
        if d is not None and not float(d) > 0:
            raise InputError("tf['density'] must be > 0, or None for automatic")
        lo, hi = rng if rng is not None else (math.nan, math.nan)
        _call(_lib.clvr_tracer_set_tf, self._h, _b(tf.get("colormap")), _b(tf.get("file")), lo, hi,
              0.0 if d is None else float(d), 1 if tf.get("ramp") else 0)

    def set_light(self, direction=(1, 2, 1.5), intensity=1.0, ambient=0.3, shadows=True):
        _call(_lib.clvr_tracer_set_light, self._h, _vec3("light direction", direction), float(intensity),
              float(ambient), 1 if shadows else 0)

    def set_background(self, rgb):
        _call(_lib.clvr_tracer_set_background, self._h, _vec3("background", rgb))

    def set_method(self, method=None, estimator=None):
        _call(_lib.clvr_tracer_set_method, self._h, _b(method), _b(estimator))

    def set_seed(self, seed):
        _call(_lib.clvr_tracer_set_seed, self._h, int(seed))
        self._seed = int(seed)

    def render(self, spp=16, camera=None, tf=None, light=None, background=None, method=None, estimator=None,
               seed=None, accumulate=False):
        """Renders spp samples per pixel and returns the image, float32
        (height, width, 4). Settings given here are applied first (each
        restarts the image); accumulate=True with no settings adds spp more
        samples to the previous image."""
        if camera is not None:
            self.set_camera(camera)
        if tf is not None:
            self.set_tf(tf)
        if light is not None:
            self.set_light(**light) if isinstance(light, dict) else self.set_light(light)
        if background is not None:
            self.set_background(background)
        if method is not None or estimator is not None:
            self.set_method(method, estimator)
        if seed is not None:
            self.set_seed(seed)
        changed = any(x is not None for x in (camera, tf, light, background, method, estimator, seed))
        if int(spp) < 1:
            raise InputError("spp must be >= 1, got %r" % spp)
        if not accumulate and not changed:
            self.set_seed(self._seed)  # the same seed again restarts the image
        _call(_lib.clvr_tracer_render, self._h, int(spp))
        return self.image()

    def image(self, denoised=False):
        """The running mean image, float32 (height, width, 4). denoised: after
        the edge-avoiding filter of clvr --denoise (a biased preview; needs the
        denoise setting before the frames)."""
        img = np.empty((self.height, self.width, 4), np.float32)
        _call(_lib.clvr_tracer_read_denoised if denoised else _lib.clvr_tracer_read_image, self._h, _ptr(img),
              img.size)
        return img

    _STATS = ("frames", "rays", "samples", "null_collisions", "kernel_s", "last_frame_s", "preprocess_s",
              "kernel_build_s", "elements", "points", "instances", "leaves", "sampling_clusters", "device_bytes",
              "density", "range_lo", "range_hi", "hull_faces", "hull_bytes", "hull_empty_fraction",
              "hull_skipped", "light_s", "image_s", "adjacency_bytes", "adjacency_skipped", "refine_pixels",
              "refine_passes", "select_s", "pilot_s", "pilot_pixels", "pilot_walk_cells")

    def stat(self, name):
        v = ctypes.c_double()
        _call(_lib.clvr_tracer_stat, self._h, _b(name), ctypes.byref(v))
        return v.value

    @property
    def stats(self):
        """Every figure of clvr_tracer_stat as a dict."""
        return {k: self.stat(k) for k in self._STATS}


def save_image(path, image, exposure=0.0, tonemap="aces", transparent=False):
    """Writes a (height, width, 4) image with the clvr program's writers,
    by extension: .png (8-bit sRGB after 2^exposure and the tone curve
    "aces", "filmic" or "none"; transparent: RGBA), .exr (float RGBA), .pfm."""
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 4 or a.dtype.kind not in "fiu":
        raise InputError("image must be a (height, width, 4) array of reals; got shape %s dtype %s"
                         % (a.shape, a.dtype))
    a = np.ascontiguousarray(a, dtype=np.float32)
    _call(_lib.clvr_image_save, _b(path), a.shape[1], a.shape[0], _ptr(a), float(exposure), _b(tonemap),
          1 if transparent else 0)


def save_png(path, image, **kw):
    save_image(path, image, **kw)


def save_exr(path, image):
    save_image(path, image)


# --------------------------------------------------------------------------- API 1.2


def setting_name(setting, index):
    """The name at index in a setting's table ("method": march, track,
    bins, dda; "estimator": delta, urm, walk, auto; "sampler": independent, ld;
    "tonemap": none, aces, filmic; "element_boxes": auto, on, off;
    "pixel_filter": box, point; "one_curve": auto, on, off), or None
    past the end or for an unknown setting. Indices are stable within a
    major version (new names are appended)."""
    n = _lib.clvr_setting_name(_text("setting", setting), _count("index", index))
    return None if n is None else n.decode()


def setting_index(setting, name):
    """The index of name in setting's table; InputError (ERR_USAGE) for an
    unknown setting or name (the message lists the names)."""
    i = _U32()
    _call(_lib.clvr_setting_index, _text("setting", setting), _text("name", name), ctypes.byref(i))
    return i.value


def setting_names(setting):
    """Every name of a setting, in index order; InputError for an unknown
    setting."""
    b = _text("setting", setting)
    names = []
    while True:
        n = _lib.clvr_setting_name(b, len(names))
        if n is None:
            break
        names.append(n.decode())
    if not names:  # every setting has a name: libclvr's message for the unknown one
        _call(_lib.clvr_setting_index, b, b"", ctypes.byref(_U32()))
    return names


def default_size():
    """(width, height) a tracer of the clvr program gets by default."""
    w, h = _U32(), _U32()
    _lib.clvr_default_size(ctypes.byref(w), ctypes.byref(h))
    return w.value, h.value


def frame_box(lo, hi, up=None, azimuth=0.0, elevation=0.0, zoom=1.0, fovy=30.0, width=None, height=None):
    """The automatic framing of Renderer.set_camera({"azimuth", "elevation",
    "zoom", "up", "fovy"}) for the box [lo, hi] and a width x height image
    (None: default_size()), without a Renderer: (eye, target), target the
    box's centre. set_camera({"eye": eye, "target": target, "up": up,
    "fovy": fovy}) then sets exactly that camera, so several meshes (a
    time series' steps) can be framed as one box. up None is +y."""
    dw, dh = default_size() if width is None or height is None else (None, None)
    w = _count("width", dw if width is None else width, 1)
    h = _count("height", dh if height is None else height, 1)
    u = None if up is None else ctypes.cast(_vec3("up", up), _P)
    eye, target = _c_float3(), _c_float3()
    _call(_lib.clvr_frame_box, _vec3("lo", lo), _vec3("hi", hi), u, float(azimuth), float(elevation), float(zoom),
          float(fovy), w, h, eye, target)
    return tuple(eye), tuple(target)


def tf_file_window(path):
    """The scalar window (lo, hi) a transfer function file fixes itself (a
    `range` line, or a ParaView map's data-space span; "FILE:NAME" for a
    ParaView preset), or None when it leaves the window to the data. The
    file is read and checked (its errors raise)."""
    has, lo, hi = ctypes.c_int(), _F(), _F()
    _call(_lib.clvr_tf_file_window, _b(path), ctypes.byref(has), ctypes.byref(lo), ctypes.byref(hi))
    return (lo.value, hi.value) if has.value else None


def is_series(path):
    """True when path names a time series file (ends in .series, any case)."""
    return bool(_lib.clvr_path_is_series(_b(path)))


class Series(_Handle):
    """A time series: a ParaView .series file ({"files": [{"name":
    "step.bin", "time": 0}, ...]}, as tools/clvr-convert writes), names
    relative to the file's folder. Only the list of steps is read here;
    len(s), s.step(i) or s[i] -> (mesh path, time), iteration over the
    steps, and bounds() loads each step in turn (Mesh.load(path) renders
    one)."""

    def __init__(self, path):
        self.path = os.fspath(path)
        self._h = _P()
        _call(_lib.clvr_series_open, _b(path), ctypes.byref(self._h))

    _destroy = staticmethod(_lib.clvr_series_destroy)

    def __len__(self):
        return _lib.clvr_series_count(self._h)

    def step(self, i):
        """(mesh path, time) of step i (time: the step's index when the file
        gives none); InputError for i >= len."""
        p, t = _S(), ctypes.c_double()
        _call(_lib.clvr_series_step, self._h, _count("step", i), ctypes.byref(p), ctypes.byref(t))
        return os.fsdecode(p.value), t.value

    def __getitem__(self, i):
        n = len(self)
        if not isinstance(i, (int, np.integer)) or isinstance(i, bool):
            raise TypeError("series steps are indexed by whole numbers, got %r" % (i,))
        if not -n <= i < n:
            raise IndexError("step %d of %s, which has %d" % (i, self.path, n))
        return self.step(int(i) % n)

    def __iter__(self):
        return (self.step(i) for i in range(len(self)))

    def bounds(self, field=None):
        """Loads every step in turn (one in memory at a time): ((xmin, ymin,
        zmin), (xmax, ymax, zmax), vmin, vmax), the union of the steps'
        bounds and field's range over all steps (field None: each file's
        first; as Mesh.load's scalar), what one camera (frame_box) and one
        colour window for the whole series need."""
        lo, hi, vmin, vmax = _c_float3(), _c_float3(), _F(), _F()
        _call(_lib.clvr_series_bounds, self._h, _b(field), lo, hi, ctypes.byref(vmin), ctypes.byref(vmax))
        return tuple(lo), tuple(hi), vmin.value, vmax.value

    def __repr__(self):
        return "clvr.Series(%r, %d steps)" % (self.path, len(self))
