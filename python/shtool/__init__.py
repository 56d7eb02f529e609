"""shtool: spherical harmonics on numpy arrays.

The runtime (evaluation, rotation, products, lighting) and the offline jobs of the
`shtool` command line, with its conventions (docs/conventions.md): order N means bands
0..N-1 (N**2 coefficients), flat index l(l+1)+m, real SH with the Condon-Shortley phase,
z up, rotation g(w) = f(R^-1 w). Coefficients lie on the last axis (``axis=`` picks
another); float32 stays float32, float64 stays float64. See docs/python.md.
"""
import errno as _errno
import functools as _functools
import inspect as _inspect
import json as _json
import numbers as _number_types
import operator as _operator
import os as _os
import re as _re
import tempfile as _tempfile
import warnings as _warnings
from dataclasses import dataclass as _dataclass

import numpy as _np

from . import _shtool
from ._shtool import __version__

# The tables the module reads (rotation helpers, zhf lobes) ship in the package's tables/
# folder (the build tree's package and the wheel): looked for after $SHTOOL_TABLES.
_shtool._set_package_tables(_os.path.join(_os.path.dirname(_os.path.abspath(__file__)), "tables"))

__all__ = [
    "eval_sh", "rotate", "quat_to_matrix", "product", "project_env", "project_env_file", "irradiance",
    "window", "light", "fit_zh", "fit_zh_mesh", "load_table", "load_zh_fit", "transform_splats", "transform_splat_arrays",
    "gen_tensors", "search_lobes", "Table", "ZhFit", "ZhFitTable", "GlossyFit", "WrinkleMap", "EnvSh",
    "RotationHelpers", "TriplingTensor", "ShFourierTensors", "ZhfLobes",
]


# A CLI option in a library message ("--threads 9", "--lobes"), not inside a quoted
# shell command (`shtool ... --out FILE`); its value when one follows.
_CLI_OPTION = _re.compile(r"`[^`]*`"
                          r"|(?<![\w-])--([a-z][a-z0-9-]*)(?: (-?[0-9.][^\s,;)]*|'[^']*'|[a-z0-9/]+(?=:)))?(:?)")


def _python_message(text, aliases):
    """The library's message with its CLI options named as this call's keywords:
    "--threads 9 is ..." -> "threads=9 is ...", "needs --half-angle" -> "needs half_angle="."""
    def keyword(m):
        if m.group(1) is None:
            return m.group(0)
        name = aliases.get(m.group(1), m.group(1).replace("-", "_"))
        if m.group(2):
            return f"{name}={m.group(2)}{m.group(3)}"
        return f"{name}{m.group(3)}" if m.group(3) else f"{name}="
    return _CLI_OPTION.sub(keyword, text)


# One parameter of pybind11's "incompatible function arguments" signature line:
# "name: type" or "name: type = default", types such as str, int, Optional[float].
_PYBIND_PARAMETER = _re.compile(r"(\w+): ([\w.]+(?:\[[\w.]+\])?)")


def _is_a(value, kind):
    """Whether pybind11 would take `value` for a parameter of the scalar type `kind`."""
    if kind == "str":
        return isinstance(value, str)
    if kind == "bool":
        return isinstance(value, (bool, _np.bool_))
    if kind == "int":
        try:
            _operator.index(value)
            return not isinstance(value, (bool, _np.bool_))
        except TypeError:
            return False
    if kind == "float":
        return isinstance(value, _number_types.Real) and not isinstance(value, (bool, _np.bool_))
    return True


def _argument_type_error(f, args, kwargs, text):
    """pybind11's "incompatible function arguments" as a TypeError naming the argument:
    the binding's scalar parameters share their names with the wrapper's."""
    listed = _re.search(r"1\. \((.*)\) ->", text)
    if listed is None:
        return None
    try:
        given = _inspect.signature(f).bind_partial(*args, **kwargs).arguments
    except TypeError:
        return None
    ints = []  # (name, value) of the integer arguments, each of the right type
    for name, kind in _PYBIND_PARAMETER.findall(listed.group(1)):
        optional = kind.startswith("Optional[")
        base = kind[len("Optional["):-1] if optional else kind
        if name not in given or base not in ("str", "int", "float", "bool"):
            continue
        value = given[name]
        if (value is None and optional) or _is_a(value, base):
            if base == "int" and value is not None:
                ints.append((name, _operator.index(value)))
            continue
        wanted = {"str": "a str", "int": "an int", "float": "a number", "bool": "a bool"}[base]
        return TypeError(f"{f.__name__}: {name} must be {wanted}{' or None' if optional else ''}, "
                         f"got {type(value).__name__}")
    # Every type right: pybind11 refused an integer its C type cannot hold; one past a C
    # int first, else a negative one (an unsigned parameter).
    for bad in (lambda v: not -2**31 <= v < 2**31, lambda v: v < 0):
        for name, value in ints:
            if bad(value):
                return ValueError(f"{f.__name__}: {name} = {value} is out of range")
    return None


_BOOLS = (bool, _np.bool_)


def _refuse_bools(f, signature, args, kwargs):
    """TypeError naming an argument given a bool where the parameter is not one (its
    default is not a bool): True would pass as 1 (order=True, an order-1 call)."""
    try:
        given = signature.bind_partial(*args, **kwargs).arguments
    except TypeError:
        return  # the call itself reports it
    for name, value in given.items():
        parameter = signature.parameters[name]
        if parameter.kind is _inspect.Parameter.VAR_KEYWORD or not isinstance(value, _BOOLS):
            continue
        default = parameter.default
        if isinstance(default, bool):
            continue
        if type(default) is int or name == "order":
            raise TypeError(f"{f.__name__}: {name} must be an int, got bool")
        if type(default) is float:
            raise TypeError(f"{f.__name__}: {name} must be a number, got bool")
        raise TypeError(f"{f.__name__}: {name} cannot be a bool, got {value!r}")


def _keywords(**aliases):
    """Bad-value errors of the decorated call name its keywords, not the CLI's options
    (`aliases`: CLI option -> keyword where they differ); a scalar argument of the wrong
    type is a TypeError naming it, not pybind11's list of signatures, and a bool is
    refused where the parameter is not one."""
    def wrap(f):
        signature = _inspect.signature(f)

        @_functools.wraps(f)
        def call(*args, **kwargs):
            if any(isinstance(v, _BOOLS) for v in args) or any(isinstance(v, _BOOLS) for v in kwargs.values()):
                _refuse_bools(f, signature, args, kwargs)
            try:
                return f(*args, **kwargs)
            except ValueError as e:
                text = str(e)
                renamed = _python_message(text, aliases)
                if renamed == text:
                    raise
                raise ValueError(renamed) from None
            except TypeError as e:
                if "incompatible function arguments" not in str(e):
                    raise
                named = _argument_type_error(f, args, kwargs, str(e))
                if named is None:
                    raise
                raise named from None
        return call
    return wrap


def _path(p, name):
    """A path argument (str, bytes or os.PathLike) as str, decoded as os.fsdecode does; a
    name that is not UTF-8 as its bytes (os.fsencode), which the module takes as they are."""
    try:
        path = _os.fsdecode(p)
    except TypeError:
        raise TypeError(f"{name} must be a path (str, bytes or os.PathLike), got {type(p).__name__}") from None
    try:
        path.encode("utf-8")
    except UnicodeEncodeError:
        return _os.fsencode(path)
    return path


def _warn_all(report, aliases=None, stacklevel=4):
    """The job's warnings (what the CLI prints as "warning:") as Python warnings, its CLI
    options named as the call's keywords (`aliases` as _keywords')."""
    report["warnings"] = [_python_message(message, aliases or {}) for message in report.get("warnings", ())]
    for message in report["warnings"]:
        _warnings.warn(message, RuntimeWarning, stacklevel=stacklevel)
    return report


def _input_path(p, name):
    """_path of a file to read; FileNotFoundError (an OSError, as open() raises) when there
    is none, before any work."""
    path = _path(p, name)
    if not _os.path.exists(path):
        raise FileNotFoundError(_errno.ENOENT, f"{name}: no such file", path)
    return path


def _float_array(x, name, integers=False):
    """x as an ndarray without copying; lists become float64, float arrays of the other byte
    order are converted to the machine's, and with `integers` (directions, rotations)
    integer arrays become float64 (other dtypes, and None: TypeError)."""
    if x is None:
        raise TypeError(f"{name} must be an array of numbers, got None")
    if isinstance(x, _np.ndarray):
        a = x
        if integers and a.dtype.kind in "iu":
            a = a.astype(_np.float64)
    else:
        try:
            a = _np.asarray(x, dtype=_np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be an array of numbers, got {type(x).__name__}") from None
    if a.dtype.kind == "f" and a.dtype.itemsize in (4, 8) and not a.dtype.isnative:
        a = a.astype(_np.float32 if a.dtype.itemsize == 4 else _np.float64)
    if a.dtype not in (_np.float32, _np.float64):
        raise TypeError(f"{name} must be float32 or float64, got {a.dtype}")
    return a


def _native_out(out):
    """`out` as given; ValueError for an array of the other byte order, which the module
    cannot write in place (it would say only that the dtype is wrong)."""
    if isinstance(out, _np.ndarray) and not out.dtype.isnative:
        raise ValueError(f"out must be in this machine's byte order, got {out.dtype.str} "
                         f"(out=out.astype(out.dtype.newbyteorder('=')) makes one)")
    return out


def _on_last_axis(a, axis, name):
    if a.ndim == 0:
        raise ValueError(f"{name} must have at least one axis")
    try:
        _operator.index(axis)
    except TypeError:
        raise TypeError(f"axis must be an int, got {type(axis).__name__}") from None
    if axis == -1 or axis == a.ndim - 1:
        return a
    if not -a.ndim <= axis < a.ndim:
        raise ValueError(f"axis={axis} is out of range for {name} of {a.ndim} dimension"
                         f"{'' if a.ndim == 1 else 's'} (shape {a.shape})")
    return _np.moveaxis(a, axis, -1)


@_keywords()
def eval_sh(order, dirs, out=None, threads=0):
    """Real SH values (..., order**2) at `dirs` (..., 3), normalised inside (a zero or
    non-finite direction: ValueError); float32 or float64 as `dirs`. `out`: a C-contiguous
    array of that shape and dtype, written in place."""
    return _shtool._eval_sh(order, _float_array(dirs, "dirs", integers=True), _native_out(out), threads)


def _back(r, axis):
    """The result's coefficient axis put where the input's was."""
    return r if axis == -1 or axis == r.ndim - 1 else _np.moveaxis(r, -1, axis)


@_keywords()
def rotate(coeffs, matrix, method="auto", axis=-1, out=None, tol=None, threads=0, tables=None):
    """Rotated coefficients g(w) = f(R^-1 w), same shape and dtype as `coeffs`.

    `matrix` is a 3x3 rotation (orthonormal to 1e-6, det +1; ValueError otherwise) or one
    per leading index, shape (..., 3, 3). `method`: auto, reference, zxzxz, taylor1,
    taylor1.5, taylor2, zhf, zhf-tailored (as ``shtool rotate --method``; the zhf methods
    take one matrix and the shipped shared lobes, orders 1 to 10). `out` (axis=-1 only): a
    C-contiguous array of the same shape and dtype, written in place. `threads`: 0 for
    every core. `tables` (``--tables``): a rotation-helpers table, or a zhf-lobes table for
    the zhf methods, instead of the shipped one (helpers for an order the shipped table
    does not cover are computed on first use, with the GIL released).
    """
    a = _on_last_axis(_float_array(coeffs, "coeffs"), axis, "coeffs")
    if out is not None and axis not in (-1, a.ndim - 1):
        raise ValueError("out= needs axis=-1")
    # The reference method reads no table (as the CLI, it passes over a missing one).
    path = "" if tables is None else _path(tables, "tables") if method == "reference" else _input_path(tables, "tables")
    return _back(_shtool._rotate(a, matrix, method, tol, _native_out(out), threads, path), axis)


@_keywords()
def quat_to_matrix(q, threads=0):
    """Rotation matrix (..., 3, 3) of unit quaternions q = (w, x, y, z) (Hamilton)."""
    return _shtool._quat_to_matrix(_float_array(q, "q", integers=True), threads)


@_keywords()
def product(a, b, order=None, method="auto", axis=-1, threads=0):
    """The SH product of a and b truncated to `order` (default: a's order).

    method: auto, tripling, fourier, grid (as ``shtool product``). Leading axes of a
    and b must agree, or one of them has none.
    """
    fa = _on_last_axis(_float_array(a, "a"), axis, "a")
    fb = _on_last_axis(_float_array(b, "b"), axis, "b")
    return _back(_shtool._product(fa, fb, order, method, threads), axis)


@_keywords()
def irradiance(coeffs, axis=-1, threads=0):
    """Irradiance coefficients E_lm = A_l L_lm (clamped cosine, no 1/pi) of radiance."""
    a = _on_last_axis(_float_array(coeffs, "coeffs"), axis, "coeffs")
    return _back(_shtool._irradiance(a, threads), axis)


@_keywords()
def window(coeffs, kind, cutoff=None, axis=-1, return_factors=False, threads=0):
    """Windowed coefficients: kind none, hann, lanczos, sinc4 or auto (as project-env).

    "auto" treats every vector of `coeffs` as one channel of one lighting (so an RGB
    lighting (N**2, 3) takes axis=0). With return_factors, also (factors per band,
    cutoff used).
    """
    a = _on_last_axis(_float_array(coeffs, "coeffs"), axis, "coeffs")
    r, factors, used = _shtool._window(a, kind, cutoff, threads)
    r = _back(r, axis)
    return (r, factors, used) if return_factors else r


@_keywords(**{"equirect-preset": "preset"})
def project_env(image, order, layout="equirect", quantity="radiance", window="none", cutoff=None,
                preset="shtool", mirror_x=False, threads=0, return_window=False):
    """Exact SH projection (order**2, C) float64 of an environment image in memory.

    `image`: float32/float64 (H, W, C) equirect (2:1, docs/lighting.md's mapping) or cross
    (4:3 / 3:4), or (6, S, S, C) faces in the order +X -X +Y -Y +Z -Z; C from 1 to 4. The
    same texel integrals, window and quantity as ``shtool project-env``: texels are read as
    float32 (float64 images are rounded to float32), sums are float64.
    """
    img = _float_array(image, "image")
    coeffs, win = _shtool._project_env(img, order, layout, quantity, window, cutoff, preset, mirror_x, threads)
    return (coeffs, _json.loads(win)) if return_window else coeffs


@_keywords()
def project_env_file(image, order=3, json=None, **options):
    """``shtool project-env`` on an image file; options as the CLI's (out=, window=,
    render_back=, ...). Returns the coefficients (order**2, 3); writes `json` (and `out`)
    when given.
    """
    with _tempfile.TemporaryDirectory() as tmp:
        path = _path(json, "json") if json is not None else _os.path.join(tmp, "lighting.json")
        image_path = _path(image, "image")
        # A face set's pattern names six files ('%s' -> px nx py ny pz nz): each is checked.
        faces = [image_path.replace("%s", f) if isinstance(image_path, str) else
                 image_path.replace(b"%s", f.encode()) for f in ("px", "nx", "py", "ny", "pz", "nz")]
        pattern = image_path != faces[0]
        for face in faces if pattern else [image_path]:
            _input_path(face, "image")
        r = _shtool._project_env_file(image_path, path, order=order, **options)
    return r["coefficients"]


_TRANSFORM_SPLATS_ALIASES = {"quat": "quaternion", "out": "path_out"}


@_keywords(**_TRANSFORM_SPLATS_ALIASES)
def transform_splats(path_in, path_out, **options):
    """``shtool transform-splats``: writes `path_out` as the CLI does. Keyword arguments:
    quaternion=(w, x, y, z) (or quat=) or matrix= (3x3, or 9 numbers row-major; a
    reflection is allowed), translate=(x, y, z), scale=, threads=, frame=, spz_frame=,
    gltf_frame=, sh_degree=, sh_bits=, spz_version=. Returns a dict (splats, degree,
    seconds, reflects, warnings); each warning (what the CLI prints as "warning:") is also
    issued as a RuntimeWarning.
    """
    return _warn_all(_shtool._transform_splats(_input_path(path_in, "path_in"), path_out, **options),
                     _TRANSFORM_SPLATS_ALIASES)


@_keywords()
def gen_tensors(order, out, **options):
    """``shtool gen-tensors``: writes the tables into the folder `out` (made if missing;
    removed again if the job fails); what=[...] (or "rotation,tripling"), inputs=,
    format=. Returns the paths written."""
    return _shtool._gen_tensors(order, out, **options)


@_keywords(dir="direction", type="kind")
def light(kind, order, direction=(0, 0, 1), half_angle=None, color=(1, 1, 1), ground=None, quantity="radiance"):
    """Analytic light as radiance (or irradiance) coefficients (order**2, 3), as
    ``shtool light``: kind directional, cone, sphere, hemisphere or constant; half_angle in
    degrees."""
    return _shtool.light(kind, order, direction, half_angle, color, ground, quantity)


def _numbers(x, count, name):
    """`count` numbers from any array-like (a 3x3 matrix for 9) as float64."""
    try:
        a = _np.asarray(x, dtype=_np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be {count} numbers, got {type(x).__name__}") from None
    if a.size != count:
        raise ValueError(f"{name} must hold {count} numbers, got shape {a.shape}")
    return a.reshape(-1)


def _splat_array(x, name, width):
    """(array as float64, dtype of the result): float32 and float64 are kept, integers are
    taken as float64 (never truncated on the way back); bools are refused, as elsewhere.
    Shape (S, width), or (S, 3, N**2) for SH colours (width None)."""
    a = _np.asarray(x)
    if a.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be an array of numbers, got {a.dtype}")
    out = _np.dtype(_np.float32 if a.dtype.kind == "f" and a.dtype.itemsize == 4 else _np.float64)
    a = a.astype(_np.float64)
    if width is None:
        k = a.shape[-1] if a.ndim == 3 else 0
        ok, text = a.ndim == 3 and a.shape[1] == 3 and k > 0 and round(k ** 0.5) ** 2 == k, "(S, 3, N**2)"
    else:
        ok, text = a.ndim == 2 and a.shape[1] == width, f"(S, {width})"
    if not ok:
        raise ValueError(f"{name} must have shape {text}, got {a.shape}")
    return a, out


@_keywords(quat="quaternion")
def transform_splat_arrays(sh=None, positions=None, rotations=None, log_scales=None, normals=None,
                           quaternion=None, matrix=None, translate=(0.0, 0.0, 0.0), scale=1.0):
    """``transform-splats`` on arrays already in memory, each optional, new arrays returned
    in a dict: positions (S, 3) -> s M p + t; rotations (S, 4) (w, x, y, z) -> q_R q (the
    Hamilton product; lengths kept); log_scales (S, 3) + log s; normals (S, 3) -> M n; sh
    (S, 3, N**2) carried along exactly (method "reference", as the job), g(w) = f(M^-1 w).
    The map as the job takes it: quaternion=(w, x, y, z) (normalised; zero refused) or
    matrix= (3x3 or 9 numbers, orthogonal to 1e-6: a rotation, or a reflection, whose
    orientations turn by its rotation part -M and whose SH get their odd bands negated), or
    neither (no turn). float32 and float64 arrays keep their dtype; integer arrays give
    float64.
    """
    if quaternion is not None and matrix is not None:
        raise ValueError("give exactly one of quaternion= and matrix=, or neither")
    # Counted here; checked (zero quaternion, matrix not orthogonal) by the job's own code.
    q = None if quaternion is None else _numbers(quaternion, 4, "quaternion")
    m = None if matrix is None else _numbers(matrix, 9, "matrix")
    if isinstance(scale, (bool, _np.bool_)) or not isinstance(scale, (int, float, _np.integer, _np.floating)):
        raise TypeError(f"scale must be a number, got {type(scale).__name__}")
    if not (scale > 0 and _np.isfinite(scale)):
        raise ValueError("scale must be a positive number")
    t = _numbers(translate, 3, "translate")
    if not _np.isfinite(t).all():
        raise ValueError("translate must be finite")
    arrays, dtypes = {}, {}
    for name, value, width in (("sh", sh, None), ("positions", positions, 3), ("rotations", rotations, 4),
                               ("log_scales", log_scales, 3), ("normals", normals, 3)):
        if value is not None:
            a, dtypes[name] = _splat_array(value, name, width)
            arrays[name] = _np.ascontiguousarray(a)
    counts = {name: a.shape[0] for name, a in arrays.items()}
    if len(set(counts.values())) > 1:
        raise ValueError("the arrays describe different numbers of splats: " +
                         ", ".join(f"{name} {count}" for name, count in counts.items()))
    # The job's own arithmetic, in float64, each result rounded once to its dtype.
    moved = _shtool._transform_splat_arrays(
        arrays.get("sh"), arrays.get("positions"), arrays.get("rotations"), arrays.get("log_scales"),
        arrays.get("normals"), None if q is None else [float(x) for x in q],
        None if m is None else [float(x) for x in m], [float(x) for x in t], float(scale))
    with _np.errstate(over="ignore"):  # checked below, with a message that says why
        out = {name: value.astype(dtypes[name], copy=False) for name, value in moved.items()}
    for name, value in out.items():
        if not _np.isfinite(value).all():
            raise ValueError(f"transform_splat_arrays: {name} overflow {value.dtype} after the transform "
                             f"(scale={scale}, translate={tuple(float(x) for x in t)})" +
                             ("; pass float64" if value.dtype == _np.float32 else ""))
    return out


@_dataclass
class ZhFit:
    """ZH lobe fits of V vectors: axes (V, lobes, 3), coeffs (V, lobes, N) (the convolved
    g*_l of each band), residual (V,) = ||fit - t||, norm (V,) = ||t||, direct (V, D)."""
    axes: _np.ndarray
    coeffs: _np.ndarray
    residual: _np.ndarray
    norm: _np.ndarray
    direct: _np.ndarray


@_keywords()
def fit_zh(transfer, lobes=4, effort=None, seed=None, starts=None, restart_above=None, direct=False,
           method="varpro", threads=0):
    """The ZH fits ``shtool fit-zh --transfer`` makes for the vectors `transfer` (V, N**2),
    computed in float64 (as the CLI) and returned in the dtype of `transfer`."""
    t = _float_array(transfer, "transfer")
    fits = _shtool._fit_zh(t, lobes, effort, seed, starts, restart_above, direct, method, threads)
    with _np.errstate(over="ignore"):  # checked below, with a message that says why
        out = [a.astype(t.dtype, copy=False) for a in fits]
    # Lobes may cancel with coefficients tens of times |t|: near float32's largest value
    # the fit does not fit float32.
    if not all(_np.isfinite(a).all() for a in out if a.dtype.kind == "f"):
        raise ValueError("fit_zh: the fit overflows %s (the vectors are too large); pass float64" % t.dtype)
    return ZhFit(*out)


def load_zh_fit(path):
    """A zh-fit table (``fit-zh --out``) as a ZhFit, checked as the runtime's loader checks it."""
    return ZhFit(*_shtool._load_zh_fit(_input_path(path, "path")))


@_keywords()
def fit_zh_mesh(mesh, out=None, **options):
    """``shtool fit-zh MESH``: simulates the transfer and fits it; options as the CLI's
    (order=, lobes=, rays=, mode=, up=, seed=, effort=, threads=, json=, ply=, shard=, ...).

    Writes `out` when given (the CLI's bytes) and returns the fits as a ZhFit; with
    shard="K/N", the partial table (a Table with `vertex_index`) for ``shtool merge``.
    """
    with _tempfile.TemporaryDirectory() as tmp:
        path = _path(out, "out") if out is not None else _os.path.join(tmp, "fit.zh.shtb")
        _warn_all(_shtool._fit_zh_mesh(_input_path(mesh, "mesh"), out=path, **options))
        if options.get("shard") is not None:
            return load_table(path)
        return load_zh_fit(path)


@_keywords()
def search_lobes(**options):
    """``shtool search-lobes``: bands=[...] (or band=l, or "a-b") or shared=True with
    order=N; out=, json=, seed=, threads=, population=, stall=, restarts=, crossover=,
    mutation=, elitism=, max_generations=, theta_candidates=, max_cond=,
    no_local_search=, no_secondary=, paper=. Returns the JSON summary as a dict."""
    if not any(options.get(k) is not None for k in ("bands", "band", "shared")):
        raise ValueError('search_lobes: give bands=[...] (or band=l, or bands="a-b"), or shared=True with order=N')
    return _json.loads(_shtool._search_lobes(**options))


class Table:
    """A loaded table: kind, order, header (dict) and arrays (read-only views of the
    loaded bytes, also reachable as attributes: ``table.coeffs``)."""

    def __init__(self, kind, order, header, arrays):
        self.kind, self.order, self.header, self.arrays = kind, order, header, arrays

    def __getattr__(self, name):
        arrays = self.__dict__.get("arrays", {})
        if name in arrays:
            return arrays[name]
        raise AttributeError(name)

    def __repr__(self):
        shapes = ", ".join(f"{k}{tuple(v.shape)}" for k, v in self.arrays.items())
        return f"{type(self).__name__}(kind={self.kind!r}, order={self.order}, arrays: {shapes})"


def load_table(path):
    """Any shtool table (binary or JSON encoding), checked as the runtime checks it. `path`:
    str, bytes or os.PathLike."""
    kind, order, header, arrays = _shtool._load_table(_input_path(path, "path"))
    return Table(kind, order, _json.loads(header), dict(arrays))


class _TypedTable(Table):
    KIND = ""

    @classmethod
    def load(cls, path):
        """The table at `path`, which must be of this kind and pass the checks of the
        engine API's loader of that kind (ValueError otherwise)."""
        kind, order, header, arrays = _shtool._load_table(_input_path(path, "path"), cls.KIND)
        return cls(kind, order, _json.loads(header), dict(arrays))


def _typed(name, kind, made_by):
    return type(name, (_TypedTable,), {"KIND": kind, "__doc__": f"{kind} tables ({made_by})."})


ZhFitTable = _typed("ZhFitTable", "zh-fit", "fit-zh: axes, coeffs, residual, norm per vertex")
GlossyFit = _typed("GlossyFit", "glossy-zh", "fit-glossy")
WrinkleMap = _typed("WrinkleMap", "wrinkle-zh", "fit-wrinkles")
EnvSh = _typed("EnvSh", "env-sh", "project-env --out, light --out: coefficients (N**2, 3)")
RotationHelpers = _typed("RotationHelpers", "rotation-helpers", "gen-tensors: the zxzxz and Taylor matrices")
TriplingTensor = _typed("TriplingTensor", "tripling-tensor", "gen-tensors")
ShFourierTensors = _typed("ShFourierTensors", "sh-fourier-tensors", "gen-tensors")
ZhfLobes = _typed("ZhfLobes", "zhf-lobes", "search-lobes --out")
