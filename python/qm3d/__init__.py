"""qm3d: visual quality metrics for coloured 3D content, from Python.

CMDM and MSDM2 score coloured meshes, PCQM coloured point clouds, with the exact numbers of the
``qm3d`` command-line tool (the same C++ library). Scores are distortions: 0 means identical,
larger is worse.

Every metric function takes a reference and a distorted object, each given as

* a file path (PLY, OBJ, OFF, PCD; recognised by content, as the tool does),
* numpy arrays: ``(positions, colors)`` for a cloud or ``(positions, colors, faces)`` for a mesh,
  as a tuple or a dict with those keys; positions ``(N, 3)`` float, colours ``(N, 3)`` uint8 0-255
  or float 0-1, faces ``(F, 3)`` integer vertex indices,
* an Open3D ``PointCloud`` or ``TriangleMesh`` (with colours),

and the tool's options as keyword arguments with the tool's names and defaults. Example::

    import qm3d
    r = qm3d.pcqm("ref.ply", "dist.ply")
    print(r.score, r.features["F4"])

The metrics release the GIL: threads (e.g. a ``concurrent.futures.ThreadPoolExecutor``) score
pairs concurrently; ``threads=`` sets the OpenMP threads of one metric as ``--threads`` does.
Results do not depend on the thread count.
"""

import inspect as _inspect
import atexit as _atexit
import json as _json
import math as _math
import os as _os
import warnings as _warnings

import numpy as _np

from . import _qm3d

__version__ = _qm3d.__version__
__commit__ = _qm3d.__commit__  # the git commit the module was built from ("unknown" outside git)

# A metric call interrupted by Ctrl-C returns at once; its worker stops at its next stage
# boundary on its own thread, and the interpreter waits for it before shutting down.
_atexit.register(_qm3d.wait_for_interrupted_calls)

InputError = _qm3d.InputError
"""A file cannot be found or read (a subclass of OSError)."""
FormatError = _qm3d.FormatError
"""A file or an array holds something malformed (a subclass of ValueError)."""
NumericError = _qm3d.NumericError
"""Well-formed input the metric cannot score, e.g. a zero-size bounding box (a ValueError)."""


class Qm3dWarning(UserWarning):
    """A metric's warning (a repair made to an input, a caveat on the score): each line of
    ``Result.warnings`` is also raised through the ``warnings`` module with this category, so
    ``warnings.simplefilter("error", qm3d.Qm3dWarning)`` or ``pytest.warns`` see it. The
    details a line leaves out are in ``Result.to_dict()["warning_details"]``."""

__all__ = ["cmdm", "msdm2", "pcqm", "pcqm_sampled", "compare", "metric", "metrics", "sample", "render", "image_quality",
           "read_mesh", "read_cloud", "evaluate", "load_model", "Result", "Direction",
           "InputError", "FormatError", "NumericError", "Qm3dWarning"]


# ---- inputs --------------------------------------------------------------------------------

def _looks_like_open3d_mesh(obj):
    return hasattr(obj, "vertices") and hasattr(obj, "triangles") and hasattr(obj, "vertex_colors")


def _looks_like_open3d_cloud(obj):
    return hasattr(obj, "points") and hasattr(obj, "colors") and not hasattr(obj, "triangles")


def _arrays_of(obj, argument):
    """(positions, colors, faces, name) of an in-memory object; faces may be None."""
    if _looks_like_open3d_mesh(obj):
        if not obj.has_vertex_colors():
            raise ValueError(f"{argument}: the Open3D TriangleMesh has no vertex colours")
        return (_np.asarray(obj.vertices), _np.asarray(obj.vertex_colors),
                _np.asarray(obj.triangles), f"<{argument}: Open3D TriangleMesh>")
    if _looks_like_open3d_cloud(obj):  # without colours: for the metrics that need none
        colors = _np.asarray(obj.colors) if obj.has_colors() else None
        return (_np.asarray(obj.points), colors, None, f"<{argument}: Open3D PointCloud>")
    if isinstance(obj, dict):
        unknown = set(obj) - {"positions", "colors", "faces", "warnings"}  # read_mesh()'s dict
        if unknown or "positions" not in obj:
            raise ValueError(f"{argument}: a dict needs 'positions', 'colors' and optionally "
                             f"'faces' (got keys {sorted(obj)})")
        return (obj["positions"], obj.get("colors"), obj.get("faces"), f"<{argument}: arrays>")
    if isinstance(obj, (tuple, list)) and len(obj) in (2, 3):
        faces = obj[2] if len(obj) == 3 else None
        return obj[0], obj[1], faces, f"<{argument}: arrays>"
    raise TypeError(f"{argument}: expected a file path, (positions, colors[, faces]) arrays, a dict "
                    f"of them, or an Open3D PointCloud / TriangleMesh; got {type(obj).__name__}")


def _array(value, argument, name):
    if value is None:
        return None
    try:
        return _np.asarray(value)
    except Exception as e:  # ragged lists and the like
        raise ValueError(f"{argument}: {name}: not an array ({e})") from None


_COLOUR_SCALES = ("auto", "unit", "byte")


def _colour_scale(value):
    """The colour_scale= keyword, checked (as --colour-scale)."""
    if value not in _COLOUR_SCALES:
        raise ValueError(f"colour_scale: expected 'auto', 'unit' or 'byte', got {value!r}")
    return value


class _Inputs:
    """The inputs of one call, built once per way a metric reads them (mesh or cloud)."""

    def __init__(self, obj, argument, colour_scale="auto", texture=None):
        self._obj, self._argument, self._made = obj, argument, {}
        if isinstance(obj, (str, bytes, _os.PathLike)):
            keyword = {"reference": "ref_texture=", "distorted": "dist_texture="}.get(
                argument, "texture=")
            self._file = _qm3d.Input.from_file(
                _os.fsdecode(obj), _colour_scale(colour_scale),
                "" if texture is None else _os.fsdecode(texture), keyword)
            self.kind = self._file.kind
        else:
            p, c, f, name = _arrays_of(obj, argument)
            self._arrays = (_array(p, argument, "positions"), _array(c, argument, "colors"),
                            _array(f, argument, "faces"), name)
            self._file = None
            self.kind = "mesh" if self._arrays[2] is not None else "cloud"

    def get(self, reads):
        if self._file is not None:
            return self._file
        if reads not in self._made:
            p, c, f, name = self._arrays
            try:
                self._made[reads] = _qm3d.Input.from_arrays(p, c, f, name, reads == "mesh")
            except ValueError as e:
                if isinstance(e, (_qm3d.FormatError, _qm3d.NumericError)):
                    raise
                raise ValueError(f"{self._argument}: {e}") from None
        return self._made[reads]

    def any(self):
        return self.get(self.kind)


# ---- results -------------------------------------------------------------------------------

class Direction:
    """One direction of a metric: which object's elements were iterated.

    Attributes:
        score: the direction's pooled score.
        features: dict of the pooled features ("f1".."f8" for CMDM/MSDM2, "F1".."F8" for PCQM)
            or of the metric's named values (psnr: "d1_mse", "d1_psnr", ...; an infinite PSNR
            is float("inf")).
        box_size: the bounding-box size that scales the metric's radii, in the object's units
            (None for psnr).
        per_element: numpy float64 array, the local distortion of each vertex / point of the
            iterated object (its input order), or None unless ``per_element=True`` was asked
            (psnr: each point's D1 error, its squared distance).
        per_element_values: dict of further per-element arrays (psnr: "d2" and "c0".."c2",
            each point's D2 and squared colour errors), empty unless ``per_element=True``.
        element_positions: numpy (n, 3) array of where each per-element value is when it is
            not on the input's elements (geodesicpsim: the keypoints of the pooled patches),
            else None.
    """

    def __init__(self, d, names):
        self.score = d.score
        if d.values:
            self.features = dict(d.values)
            self.box_size = None
        else:
            self.features = dict(zip(names, d.feature_values))
            self.box_size = d.box_size
        self.per_element = d.per_element
        self.per_element_values = dict(d.per_element_values)
        self.element_positions = d.element_positions

    def __repr__(self):
        return f"Direction(score={self.score!r})"


class Result:
    """The result of one metric on one pair.

    Attributes:
        metric: "cmdm", "msdm2", "pcqm", ...
        score: the requested direction's score, or the mean of both (symmetric).
        dist_to_ref / ref_to_dist: a Direction, or None when not computed.
        directions: dict of the computed directions by name.
        features: the features of the single computed direction (None when both were computed);
            for a metric of named values (psnr) the result's own: the symmetric values (each
            the worse direction's, as pc_error's "Final") or the single direction's.
        box_size, per_element: likewise, of the single computed direction.
        details: dict of the metric's further values (psnr: peak, peak_source, nn_min /
            nn_max, points_reference, points_distorted, duplicates_reference,
            duplicates_distorted, normals), as in the JSON.
        warnings: list of str (repairs made to the inputs, caveats), as the tool prints them;
            each is also raised as a Qm3dWarning (warnings module) when the metric returns.
        seconds: wall time of the computation.
    """

    def __init__(self, r):
        self._r = r
        self.metric = r.metric
        self.score = r.score
        names = list(r.feature_names)
        self.dist_to_ref = Direction(r.dist_to_ref, names) if r.dist_to_ref is not None else None
        self.ref_to_dist = Direction(r.ref_to_dist, names) if r.ref_to_dist is not None else None
        self.directions = {k: v for k, v in (("dist_to_ref", self.dist_to_ref),
                                             ("ref_to_dist", self.ref_to_dist)) if v is not None}
        single = next(iter(self.directions.values())) if len(self.directions) == 1 else None
        self.features = dict(r.values) if r.values else single.features if single else None
        self.box_size = single.box_size if single else None
        self.per_element = single.per_element if single else None
        self.warnings = list(r.warnings)
        self.seconds = r.seconds
        self.details = _json.loads(r.details_json)

    def to_dict(self):
        """The object ``qm3d <metric> --json`` writes for this result."""
        return _json.loads(self._r.to_json())

    def csv_row(self, value_names=None):
        """The row ``qm3d <metric> --csv`` (and ``batch``) writes for this result, under
        ``csv_header(value_names)`` (default: this metric's named-value columns)."""
        if value_names is None:
            value_names = _SPECS[self.metric]["value_names"] if self.metric in _SPECS else []
        return self._r.csv_row(list(value_names))

    def __repr__(self):
        return f"Result(metric={self.metric!r}, score={self.score!r})"


# ---- metrics -------------------------------------------------------------------------------

_SPECS = {}
for _s in _qm3d.metrics():
    for _o in _s["options"]:
        _o["default"] = _json.loads(_o["default"])
    _SPECS[_s["name"]] = _s

def _installed_tables():
    """The tables installed with the package: qm3d/lab2000hl inside it (a wheel, setup.py),
    else PREFIX/share/qm3d/lab2000hl beside a package installed by CMake (PREFIX/lib/python3.X/
    dist-packages/qm3d), as the installed tool finds its tables; None elsewhere (a build tree)."""
    here = _os.path.dirname(_os.path.realpath(__file__))
    prefix = _os.path.dirname(_os.path.dirname(_os.path.dirname(_os.path.dirname(here))))
    for tables in (_os.path.join(here, "lab2000hl"),
                   _os.path.join(prefix, "share", "qm3d", "lab2000hl")):
        if _os.path.isfile(_os.path.join(tables, "L_data.txt")):
            return tables
    return None


# The tables: data_dir=, else $QM3D_DATA_DIR, else the installation's own (the wheel's, then
# PREFIX/share), else the build-time directory (the tool's order).
_DEFAULT_TABLES = None if _os.environ.get("QM3D_DATA_DIR") else _installed_tables()

_RUN_KEYWORDS = ("direction", "threads", "per_element", "data_dir", "weights", "model",
                 "progress", "colour_scale", "ref_texture", "dist_texture")


def metrics():
    """Every metric qm3d has, as dicts: name, title, summary, applies_to ("meshes", "clouds",
    "both"), reads ("mesh" or "cloud"), default_direction, takes_model, higher_is_better (True
    when the score is a quality, like PSNR; False for a distortion, 0 = identical), value_names
    (the named values of ``MetricResult.values``), quality_value_names (those of them that are
    qualities) and options (each with name, help, default, choices, min, max)."""
    return [dict(s) for s in _SPECS.values()]


def _option_value(spec, option, value):
    default = option["default"]
    name = f"{spec['name']}: {option['name']}"
    if isinstance(default, bool):
        if not isinstance(value, (bool, _np.bool_)):
            raise ValueError(f"{name}: expected True or False, got {value!r}")
        return bool(value)
    if isinstance(default, int):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if not isinstance(value, (int, _np.integer)) or isinstance(value, bool):
            raise ValueError(f"{name}: expected an integer, got {value!r}")
        return int(value)
    if isinstance(default, float):
        if not isinstance(value, (int, float, _np.integer, _np.floating)) or isinstance(value, bool):
            raise ValueError(f"{name}: expected a number, got {value!r}")
        return _finite(name, value)
    if isinstance(default, list):
        return [_finite(name, v) for v in value]
    if isinstance(default, str) and isinstance(value, _os.PathLike):
        return _os.fspath(value)  # a file option (graphsim's keypoint_file) given as a Path
    return value


def _thread_count(threads):
    if isinstance(threads, bool) or not isinstance(threads, (int, _np.integer)):
        raise ValueError(f"threads: expected an integer, got {threads!r}")
    if not 0 <= threads <= 2**31 - 1:
        raise ValueError(f"threads: expected 0 (all cores) or a positive count, got {threads}")
    return int(threads)


def _finite(name, value):
    # JSON has no NaN or infinity: a non-finite option is refused here, as the tool refuses it.
    # A string or a flag is not a number, even when it reads as one.
    if isinstance(value, (str, bytes, bool, _np.bool_)):
        raise ValueError(f"{name}: expected a number, got {value!r}")
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a number, got {value!r}") from None
    if not _math.isfinite(value):
        raise ValueError(f"{name}: expected a finite number, got {value!r}")
    return value


def _run(name, reference, distorted, kwargs, ref_inputs=None, dist_inputs=None, release=False):
    spec = _SPECS[name]
    known = {o["name"]: o for o in spec["options"]}
    options = {}
    run = dict(direction=None, threads=0, per_element=False, data_dir=None, weights=None,
               model=None, progress=None, colour_scale="auto", ref_texture=None,
               dist_texture=None)
    for key, value in kwargs.items():
        if key in run:
            run[key] = value
        elif key in known:
            options[key] = _option_value(spec, known[key], value)
        else:
            raise TypeError(f"{name}() got an unexpected keyword argument {key!r} (options: "
                            f"{', '.join(list(known) + list(_RUN_KEYWORDS))})")
    if run["direction"] is not None and run["direction"] not in (
            "symmetric", "dist-to-ref", "ref-to-dist"):
        raise ValueError(f"direction: expected 'symmetric', 'dist-to-ref' or 'ref-to-dist', got "
                         f"{run['direction']!r}")
    if run["model"] is not None and run["weights"] is not None:
        raise ValueError("give weights or model, not both")
    model_path = None
    if run["model"] is not None:
        model = run["model"]
        if isinstance(model, dict):
            if model.get("metric") != spec["model_metric"]:
                raise ValueError(f"model: a {model.get('metric')!r} model, not a "
                                 f"{spec['model_metric']!r} one")
            run["weights"] = model_weights(model)
        else:
            model_path = _os.fsdecode(model)
    weights = (None if run["weights"] is None
               else [_finite(f"{name}: weights", w) for w in run["weights"]])
    # Inputs made for this call alone are freed as soon as the metric holds its own copies.
    release = release or (ref_inputs is None and dist_inputs is None)
    ref_inputs = ref_inputs or _Inputs(reference, "reference", run["colour_scale"],
                                       run["ref_texture"])
    dist_inputs = dist_inputs or _Inputs(distorted, "distorted", run["colour_scale"],
                                         run["dist_texture"])
    reads = spec["reads"]
    if spec["reads_two_meshes_as_meshes"] and ref_inputs.kind == dist_inputs.kind == "mesh":
        reads = "mesh"  # the metric dispatches on the pair (dlab: meshes by projection)
    ref_reads = ref_inputs.kind if spec["reads_each_as_is"] else reads
    dist_reads = dist_inputs.kind if spec["reads_each_as_is"] else reads
    result = _qm3d.run(name, ref_inputs.get(ref_reads), dist_inputs.get(dist_reads),
                       _json.dumps(options), run["direction"], _thread_count(run["threads"]),
                       bool(run["per_element"]),
                       _os.fsdecode(run["data_dir"]) if run["data_dir"] is not None
                       else (_DEFAULT_TABLES or ""),
                       weights, model_path, run["progress"], release)
    out = Result(result)
    for line in out.warnings:
        # stacklevel 3: the caller of qm3d.<metric>() or metric().
        _warnings.warn(line, Qm3dWarning, stacklevel=3)
    return out


def metric(name, reference, distorted, **options):
    """Runs the metric called `name` (see metrics()) on a pair; keyword arguments as for the
    metric's own function."""
    if name not in _SPECS:
        raise ValueError(f"unknown metric {name!r} (expected {', '.join(_SPECS)})")
    return _run(name, reference, distorted, options)


_COMMON_DOC = """
    Args:
        reference, distorted: a file path; (positions, colors[, faces]) numpy arrays or a dict
            of them (positions (N, 3) float in the object's units; colors (N, 3) uint8 0-255 or
            float 0-1; faces (F, 3) integer vertex indices); or an Open3D PointCloud /
            TriangleMesh with colours.
        direction: "symmetric", "dist-to-ref" or "ref-to-dist" (default: {default}). {dhelp}
        threads: OpenMP threads (0 = all cores), as --threads; results do not depend on it.
        per_element: keep the per-vertex / per-point local distortion as numpy arrays.
        data_dir: folder of the LAB2000HL tables (default: $QM3D_DATA_DIR, else the
            installed package's own, else the folder configured when it was built).
        colour_scale: "auto", "unit" or "byte", as --colour-scale: the scale of colours stored
            as numbers in files (OBJ, OFF, PLY float). auto = the reference's rule (0..255 when
            any value is above 1; warns when few values decide), unit = 0..1 (values above 1
            clamped), byte = 0..255.
        ref_texture, dist_texture: a texture map (PNG, JPEG, BMP, TGA) replacing the
            reference's / distorted mesh's own, as --ref-texture / --dist-texture (mmetric's
            --inputMapA / --inputMapB): every face with texture coordinates takes its colour
            from it.
{model}        progress: optional callable(stage: str, fraction: float), told each stage.
{options}
    Returns:
        Result (score, directions with features, box size and optional per-element values,
        warnings, to_dict() = the tool's --json object).

    Raises:
        InputError (an OSError) for a file that cannot be read; FormatError / ValueError for
        malformed files or arrays (naming the argument); NumericError for input the metric
        cannot score.
"""


def _make_metric_function(spec):
    name = spec["name"]

    def function(reference, distorted, **options):
        return _run(name, reference, distorted, options)

    params = [_inspect.Parameter("reference", _inspect.Parameter.POSITIONAL_OR_KEYWORD),
              _inspect.Parameter("distorted", _inspect.Parameter.POSITIONAL_OR_KEYWORD)]
    kw = _inspect.Parameter.KEYWORD_ONLY
    params += [_inspect.Parameter("direction", kw, default=None),
               _inspect.Parameter("threads", kw, default=0),
               _inspect.Parameter("per_element", kw, default=False),
               _inspect.Parameter("data_dir", kw, default=None),
               _inspect.Parameter("colour_scale", kw, default="auto"),
               _inspect.Parameter("ref_texture", kw, default=None),
               _inspect.Parameter("dist_texture", kw, default=None)]
    if spec["takes_model"]:
        params += [_inspect.Parameter("weights", kw, default=None),
                   _inspect.Parameter("model", kw, default=None)]
    params.append(_inspect.Parameter("progress", kw, default=None))
    params += [_inspect.Parameter(o["name"], kw, default=o["default"]) for o in spec["options"]]
    function.__signature__ = _inspect.Signature(params)
    function.__name__ = function.__qualname__ = name
    model_doc = ("        weights: 8 weights of the features replacing the published model.\n"
                 "        model: a model file (qm3d train) or a dict from load_model().\n"
                 if spec["takes_model"] else "")
    option_doc = "".join(f"        {o['name']}: {o['help']} (default {o['default']!r}).\n"
                         for o in spec["options"])
    function.__doc__ = spec["summary"] + "." + _COMMON_DOC.format(
        default=spec["default_direction"], dhelp=spec["direction_help"], model=model_doc,
        options=option_doc)
    return function


for _name, _spec in _SPECS.items():
    globals()[_name] = _make_metric_function(_spec)


def compare(reference, distorted, **options):
    """Every metric that applies to the pair (as ``qm3d compare``), in the registry's order:
    CMDM, MSDM2, PCQM, pcqm_sampled and D_LAB for two meshes; PCQM, PSNR and D_LAB for two
    clouds; PCQM and D_LAB for a mesh and a cloud (ibsm only by name: ``qm3d.ibsm``). Keyword
    arguments go to every metric that has
    them (e.g. scales=, radius=, points=); run options (direction, threads, per_element,
    data_dir, progress) to all; ``model`` (a file) applies to the metric it names.

    Returns:
        dict metric name -> Result, in the tool's order.
    """
    if "weights" in options:
        raise TypeError("compare(): weights apply to one metric; give model= (a model file "
                        "names its metric) or call the metric")
    _check_option_names("compare", options)
    scale = options.get("colour_scale", "auto")
    ref_inputs = _Inputs(reference, "reference", scale, options.get("ref_texture"))
    dist_inputs = _Inputs(distorted, "distorted", scale, options.get("dist_texture"))
    out = {}
    names = _qm3d.applicable(ref_inputs.any(), dist_inputs.any())
    for i, name in enumerate(names):
        out[name] = _run(name, None, None, _options_for(name, options), ref_inputs, dist_inputs,
                         release=i == len(names) - 1)
    return out


def _check_option_names(caller, options):
    """TypeError for a keyword no metric knows (each metric takes the ones it knows)."""
    known = set(_RUN_KEYWORDS) | {o["name"] for s in _SPECS.values() for o in s["options"]}
    unknown = sorted(set(options) - known)
    if unknown:
        raise TypeError(f"{caller}() got unexpected keyword arguments {unknown}")


def _options_for(name, options):
    """The options of a set given to several metrics that metric `name` takes: its own, the run
    options, and a model only when it names this metric's model."""
    spec = _SPECS[name]
    known = {o["name"] for o in spec["options"]} | set(_RUN_KEYWORDS)
    mine = {k: v for k, v in options.items() if k in known}
    model = mine.get("model")
    if model is not None:
        model_metric = (model if isinstance(model, dict) else load_model(model))["metric"]
        if not spec["takes_model"] or spec["model_metric"] != model_metric:
            del mine["model"]
    return mine


# ---- tools ---------------------------------------------------------------------------------

def read_mesh(path, colour_scale="auto", texture=None):
    """Reads a mesh file (OBJ, OFF, PLY; a textured mesh gets its texture's colours) as qm3d's
    metrics read it (colour_scale as for the metrics; texture: a map replacing the file's own,
    as --texture).

    Returns:
        dict: positions (V, 3) float64, colors (V, 3) float64 in 0-1 (None when the file has
        none), faces (F, 3) uint32, warnings (list of str: repairs made, e.g. vertices no face
        uses dropped).
    """
    p, c, f, w = _qm3d.Input.from_file(
        _os.fsdecode(path), _colour_scale(colour_scale),
        "" if texture is None else _os.fsdecode(texture), "texture=").mesh_arrays()
    return {"positions": p, "colors": c, "faces": f, "warnings": list(w)}


def read_cloud(path, colour_scale="auto"):
    """Reads a point cloud (PLY, PCD), or a mesh file's vertices, as PCQM reads it
    (colour_scale as for the metrics).

    Returns:
        dict: positions (N, 3) float64, colors (N, 3) float64 in 0-1, warnings (list of str:
        e.g. a colour scale chosen on few values, float32 coordinates that lost detail).
    """
    p, c, w = _qm3d.Input.from_file(_os.fsdecode(path),
                                    _colour_scale(colour_scale)).cloud_arrays()
    return {"positions": p, "colors": c, "warnings": list(w)}


def sample(mesh, points=None, density=None, seed=1, mode="random", grid_size=1024, box=None,
           all_axes=False, bilinear=False, texture=None):
    """Samples a mesh's surface into a coloured point cloud, as ``qm3d sample`` does.

    Args:
        mesh: a mesh file, (positions, colors, faces) arrays or a dict of them, or an Open3D
            TriangleMesh.
        mode: "random" (area-uniform; colours interpolated, or from the texture of a textured
            OBJ) or "grid" (MPEG mmetric's ``mm sample --mode grid --useNormal``: the samples
            the V-DMC CTC's PSNR compares).
        points: random mode: number of samples; or
        density: random mode: samples per unit area (the mesh's units^-2).
        seed: random mode: the random seed (same seed, same cloud on any machine).
        grid_size: grid mode: grid nodes along the box's longest side (mmetric --gridSize).
        box: grid mode: (min x, min y, min z, max x, max y, max z) of the grid (mmetric
            --minPos / --maxPos); None = the mesh's own vertex box.
        all_axes: grid mode: rays along all three axes (mmetric without --useNormal).
        bilinear: grid mode: bilinear texture lookups (mmetric --bilinear).
        texture: a texture map replacing the mesh file's own, as --texture (mmetric's
            --inputMap): every face with texture coordinates takes its colour from it.

    Returns:
        dict: positions (N, 3) float64, colors (N, 3) float64 in 0-1 (grid mode: the float32
        values and 8-bit colours mmetric writes; plus normals (N, 3), the faces' normals,
        step, degenerate_faces and warnings).
    """
    if mode == "grid":
        if points is not None or density is not None:
            raise ValueError("sample: points and density apply to mode='random'")
        inputs = _Inputs(mesh, "mesh", texture=texture)
        p, n, c, w, degenerate, step = _qm3d.sample_grid(
            inputs.get("mesh"), int(grid_size), None if box is None else [float(v) for v in box],
            bool(all_axes), bool(bilinear))
        return {"positions": p, "normals": n, "colors": c if len(c) else None, "step": step,
                "degenerate_faces": degenerate, "warnings": list(w)}
    if mode != "random":
        raise ValueError(f"sample: mode must be 'random' or 'grid', got {mode!r}")
    if (points is None) == (density is None):
        raise ValueError("sample: give exactly one of points and density")
    inputs = _Inputs(mesh, "mesh", texture=texture)
    p, c = _qm3d.sample(inputs.get("mesh"), int(points or 0), float(density or 0), int(seed))
    return {"positions": p, "colors": c}


def render(obj, *, views=16, resolution=2048, rotation=(0.0, 0.0, 0.0), layout="fibonacci",
           culling=True, lighting="none", splat_size=0.0, splat_shape="disc", frame=None,
           threads=0, colour_scale="auto", texture=None):
    """Renders an object as ``qm3d ibsm`` sees it: orthographic views from the same cameras,
    with the same rasteriser (mmetric's sw_raster for meshes, splats for clouds).

    Args:
        obj: a mesh or point cloud: a file path, (positions, colors[, faces]) arrays or a dict
            of them, or an Open3D PointCloud / TriangleMesh (as the metric functions take).
        views, resolution, rotation, layout, lighting, splat_size, splat_shape: as ``ibsm``'s
            options (``views`` is the Fibonacci layout's count; ``layout="cmdm18"`` gives the
            CMDM report's 18 directions).
        culling: back-face culling (ibsm's ``no_culling`` inverted).
        frame: (centre x, y, z, radius) of the bounding sphere the cameras are framed on, e.g.
            ``result.to_dict()["bsphere_center"] + [result.to_dict()["bsphere_radius"]]`` of an
            ibsm result to get its images exactly; None = the object's own (its box's centre and
            half diagonal + 1 %).
        threads: OpenMP threads (0 = all cores); the images do not depend on it.
        texture: a texture map replacing the mesh file's own (as ``ibsm``'s ``ref_texture``).

    Returns:
        dict: ``views``, a list (one per view) of dicts with ``direction`` (3 floats, from the
        centre towards the camera), ``rgb`` (H, W, 3) uint8, ``mask`` (H, W) bool (drawn
        pixels), ``depth`` (H, W) float32 (larger = nearer; NaN where nothing is drawn) and
        ``depth_range`` (the frame's depth span, ibsm's depth scale), rows top first; and
        ``frame`` (centre, radius).
    """
    spec = _SPECS["ibsm"]
    given = {"views": views, "resolution": resolution, "rotation": list(rotation),
             "layout": layout, "no_culling": not culling, "lighting": lighting,
             "splat_size": splat_size, "splat_shape": splat_shape}
    by_name = {o["name"]: o for o in spec["options"]}
    options = {k: _option_value(spec, by_name[k], v) for k, v in given.items()}
    if frame is not None:
        frame = [_finite("frame", v) for v in frame]
    inputs = _Inputs(obj, "obj", colour_scale, texture)
    out, centre, radius = _qm3d.render_views(inputs.any(), _json.dumps(options),
                                             frame, _thread_count(threads))
    result = []
    for direction, rgba, depth, depth_range in out:
        result.append({"direction": list(direction), "rgb": rgba[:, :, :3].copy(),
                       "mask": rgba[:, :, 3] != 0, "depth": depth, "depth_range": depth_range})
    return {"views": result, "frame": {"center": list(centre), "radius": radius}}


def _finite_array(name, a):
    if not _np.all(_np.isfinite(a)):
        raise ValueError(f"{name}: NaN or infinite values")
    return a


def evaluate(scores, mos, ci95=None, bootstrap=1000, seed=1, sd=None, n=None, raw=None,
             pairs=None, groups=None, lower_is_better=(), orientation="auto", mapping=None):
    """Agreement of objective scores with subjective ones, as ``qm3d eval``.

    One metric (`scores` a sequence, no pair data): PLCC, SROCC, KROCC, PLCC and RMSE after the
    logistic mapping, and the outlier ratio when `ci95` is given, each with a 95% bootstrap
    interval (stimuli resampled, the logistic refitted).

    Several metrics (`scores` a dict {name: sequence}, or a pandas DataFrame), or any pair data:
    the same per metric side by side, plus Krasula's AUC analysis and the tests between metrics
    when pairs can be labelled — from `sd` and `n` (per-stimulus standard deviation and observer
    count: Krasula's one-sided 95% z test), from `raw` (a sequence per stimulus of its individual
    scores: VMAF's |z| > 2 rule on every ordered pair) or given as `pairs` ((first, second,
    label) triples of stimulus indices, label 1 = first better, -1 worse, 0 similar); `groups`
    (one value per stimulus) keeps the pairs within a group. Registered metrics' names (and their
    named values, e.g. ``d1_mse``) give their orientation; others are taken as qualities unless
    named in `lower_is_better` (or `orientation` = "quality" / "distortion" for all). `mapping`
    (as ``qm3d eval --mapping``: none, linear, cubic, logistic4, logistic5; default logistic4)
    selects this protocol for one metric too; with none or linear 3 stimuli are enough (the
    logistic needs 5).

    Args:
        scores: a sequence, or a dict / DataFrame of sequences, of the same length as `mos`.
        mos: subjective scores; ci95: optional 95% CI half-widths of the MOS.
        bootstrap, seed: replicates (0 = no intervals) and the seed.

    Returns:
        dict. One metric: stimuli, statistics {name: {value, ci95}}, logistic, bootstrap.
        Several: stimuli, metrics {NAME: {orientation, statistics {plcc, srocc, krocc,
        plcc_mapped, rmse_mapped[, outlier_ratio]}, mapping, bootstrap, krasula {auc_ds, auc_bw,
        c0, thr, thr_prctile, se_ds, se_bw, different, similar} or None}}, krasula {rule, pairs,
        different, better, similar} or None, comparisons [{a, b, test, statistic, p}].
    """
    m = _finite_array("mos", _np.asarray(mos, dtype=float).ravel())
    c = _finite_array("ci95", _np.asarray(ci95 if ci95 is not None else [], dtype=float).ravel())
    if c.size not in (0, m.size):
        raise ValueError(f"ci95: {c.size} values for {m.size} stimuli")
    several = isinstance(scores, dict) or hasattr(scores, "columns")
    if not several and sd is None and raw is None and pairs is None and mapping is None:
        s = _finite_array("scores", _np.asarray(scores, dtype=float).ravel())
        if s.size != m.size:
            raise ValueError(f"scores and mos: {s.size} scores but {m.size} MOS values")
        return _json.loads(_qm3d.evaluate(s.tolist(), m.tolist(), c.tolist(), int(bootstrap),
                                          int(seed)))
    if not several:
        scores = {"score": scores}
    names = [str(k) for k in scores.keys()] if isinstance(scores, dict) else [str(k) for k in scores.columns]
    series = []
    for name in names:
        s = _finite_array(f"scores[{name!r}]", _np.asarray(scores[name], dtype=float).ravel())
        if s.size != m.size:
            raise ValueError(f"scores[{name!r}]: {s.size} scores but {m.size} MOS values")
        series.append(s.tolist())
    if sum(x is not None for x in (sd, raw, pairs)) > 1:
        raise ValueError("give one of sd (with n), raw and pairs")
    labels, sdv, nv, rawv, first, second, label = "", [], [], [], [], [], []
    if sd is not None:
        if n is None:
            raise ValueError("sd needs n (the observer count of each stimulus)")
        sdv = _finite_array("sd", _np.asarray(sd, dtype=float).ravel()).tolist()
        nv = _finite_array("n", _np.asarray(n, dtype=float).ravel()).tolist()
        if len(sdv) != m.size or len(nv) != m.size:
            raise ValueError(f"sd and n: one value per stimulus ({m.size}) needed")
        labels = "sd"
    elif raw is not None:
        rawv = [_finite_array(f"raw[{i}]", _np.asarray(r, dtype=float).ravel()).tolist() for i, r in enumerate(raw)]
        if len(rawv) != m.size:
            raise ValueError(f"raw: {len(rawv)} stimuli for {m.size} MOS values")
        labels = "raw"
    elif pairs is not None:
        for k, (a, b, l) in enumerate(pairs):
            if not (0 <= int(a) < m.size and 0 <= int(b) < m.size) or int(l) not in (-1, 0, 1):
                raise ValueError(f"pairs[{k}]: stimulus indices 0..{m.size - 1} and a label -1, 0 or 1 needed")
            if int(a) == int(b):
                raise ValueError(f"pairs[{k}]: stimulus {int(a)} is paired with itself")
            first.append(int(a)); second.append(int(b)); label.append(int(l))
        labels = "pairs"
    g = [str(x) for x in groups] if groups is not None else []
    if g and len(g) != m.size:
        raise ValueError(f"groups: {len(g)} values for {m.size} stimuli")
    if orientation not in ("auto", "quality", "distortion"):
        raise ValueError("orientation: auto, quality or distortion")
    unknown = [str(x) for x in lower_is_better if str(x) not in names]
    if unknown:
        raise ValueError(f"lower_is_better: {', '.join(unknown)}: no such metric "
                         f"(the metrics: {', '.join(names)})")
    return _json.loads(_qm3d.evaluate_metrics(
        names, series, [str(x) for x in lower_is_better], orientation, m.tolist(), c.tolist(),
        labels, sdv, nv, rawv, first, second, label, g, int(bootstrap), int(seed),
        "logistic4" if mapping is None else str(mapping)))


def load_model(path):
    """Reads a model file (written by ``qm3d train``): dict with metric, features, weights and
    the optional MOS mapping. Pass it (or the path) as ``model=`` to cmdm() / pcqm()."""
    return _json.loads(_qm3d.load_model(_os.fsdecode(path)))


def model_weights(model):
    """The 8 feature weights of a model dict (load_model()), in f1..f8 order."""
    weights = [0.0] * 8
    for name, w in zip(model["features"], model["weights"]):
        weights[int(name[1:]) - 1] = float(w)
    return weights


def _image_array(image, argument):
    array = _np.asarray(image)
    if array.dtype != _np.uint8:
        raise ValueError(f"{argument}: expected a uint8 array (8-bit sRGB), got {array.dtype}")
    if array.ndim != 3 or array.shape[2] not in (3, 4) or array.shape[0] < 1 or array.shape[1] < 1:
        raise ValueError(f"{argument}: expected an (H, W, 3) or (H, W, 4) array, got shape "
                         f"{array.shape}")
    return _np.ascontiguousarray(array)


def image_quality(a, b, *, intent="perceptual", iam=True, omit_maps67=False, downsampling=True,
                  return_map=False, threads=0, data_dir=None):
    """Compares two 8-bit sRGB images as ``qm3d image A B`` does.

    Args:
        a, b: (H, W, 3) or (H, W, 4) uint8 arrays of the same size, rows top first (a 4th
            channel, alpha, is dropped, as the iCID reference's imread does).
        intent: iCID's prediction intent: "perceptual", "hue-preserving" or "chromatic".
        iam: iCID's image-appearance model (CSF filtering); False = the reference's IAM 'NONE'.
        omit_maps67: leave out iCID's chroma contrast and chroma structure maps.
        downsampling: iCID's automatic downsampling to ~256 px on the shorter side.
        return_map: also return the per-pixel iCID map.
        threads: OpenMP threads (0 = all cores); the values do not depend on it.
        data_dir: folder of the LAB2000HL tables (iCID reads their full-precision copy in its
            ``icid`` subfolder); default as the metric functions.

    Returns:
        dict: ``icid`` (0 = identical), ``icid_m1`` .. ``icid_m7`` (the means of iCID's seven
        maps: lightness difference, lightness contrast, lightness structure, chroma difference,
        hue difference, chroma contrast, chroma structure), ``ssim``, ``ms_ssim`` (of the BT.709
        luma over the whole image) and ``psnr`` (of R, G, B; inf for identical images). With
        ``return_map``: (that dict, the (H', W') float64 map, the (downsampled) image less a
        5-pixel border).
    """
    if intent not in ("perceptual", "hue-preserving", "chromatic"):
        raise ValueError(f"intent: expected 'perceptual', 'hue-preserving' or 'chromatic', got "
                         f"{intent!r}")
    values, pixel_map = _qm3d.image_quality(
        _image_array(a, "a"), _image_array(b, "b"), intent, bool(iam), bool(omit_maps67),
        bool(downsampling), bool(return_map), _thread_count(threads),
        _os.fsdecode(data_dir) if data_dir is not None else (_DEFAULT_TABLES or ""))
    return (values, pixel_map) if return_map else values
