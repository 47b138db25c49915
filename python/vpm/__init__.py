"""vpm: volume-preserving mapping and registration of 3-D shapes to the unit ball.

The Python face of the vpm library (docs/python.md): the same C++ code as the `vpm` command,
with NumPy arrays in and out. Meshes (`vpm.Mesh`) and images (`vpm.Image`) own their memory and
show it to NumPy as views, so arrays come out without copies and go back in without copies;
arrays made elsewhere are copied once into the library's layout. Library errors keep their
messages: bad input raises ValueError, a numerical failure vpm.NumericalError. Long calls release
the GIL. Every call runs on the device `device=` names ('host', 'cpu', 'gpu', 'P:D' or part of a
name), else on select_device()'s, else on VPM_DEVICE's (docs/design.md 3).

    import vpm
    mesh, _ = vpm.mesh_image("/usr/share/mricron/templates/ch2bet.nii.gz",
                             labels="/usr/share/mricron/templates/aal.nii.gz")
    ball, report = vpm.map_to_ball(mesh)
    print(report.final.vertex_volume_ratio.mean_abs_dev)
"""
import json
import os
import sys
from dataclasses import dataclass, field

import numpy as np

from ._vpm import (Elements, ElementTable, Image, InitialMapReport, MapMetrics, MapReport, Mesh,  # noqa: F401
                   NumericalError, RatioStats, RegistrationReport, Report, SurfaceMapReport, SurfaceMetrics,
                   __version__, device_name, devices,
                   read_image, read_label_names, read_mesh, read_table, select_device, to_image, to_native,
                   validate, write_mesh, write_nifti)
from . import _vpm

__all__ = ["Mesh", "Image", "Elements", "ElementTable", "Comparison", "NumericalError", "MapReport",
           "InitialMapReport", "RegistrationReport", "MapMetrics", "RatioStats", "Report", "SurfaceMapReport",
           "SurfaceMetrics", "read_surface", "read_overlay", "write_surface", "map_to_sphere", "map_to_disk", "register_on_sphere", "register_in_disk", "locate_on_sphere", "mean_curvature",
           "read_mesh", "write_mesh", "validate", "read_image", "write_nifti", "image", "mesh_image",
           "initial_map", "map_to_ball", "register", "elements", "sample", "calibrate", "compare", "read_table",
           "to_native", "to_image", "read_label_names", "devices", "select_device", "device_name"]


def _progress(progress, what):
    """(callback for the library, bar to close) for progress=None | False | True | callable."""
    if progress is None or progress is False:
        return None, None
    if callable(progress):
        return progress, None
    try:
        from tqdm.auto import tqdm
    except ImportError:  # no tqdm: the library's lines on stderr
        return (lambda line: print(f"vpm {what}: {line}", file=sys.stderr)), None
    bar = tqdm(desc=f"vpm {what}", unit=" step")

    def step(line):
        bar.set_postfix_str(line[:70], refresh=False)
        bar.update(1)
    return step, bar


def _call(fn, progress, what, *args, **kwargs):
    callback, bar = _progress(progress, what)
    try:
        return fn(*args, progress=callback, **kwargs)
    finally:
        if bar is not None:
            bar.close()


def image(source, affine=None):
    """A vpm.Image from a path (NIfTI .nii/.nii.gz or FreeSurfer .mgh/.mgz, read by vpm), a
    nibabel image (its data and affine; one copy), a vpm.Image (as it is) or a 3-D array with
    its 4 x 4 voxel -> world (mm) `affine`."""
    if isinstance(source, Image):
        return source
    if isinstance(source, (str, os.PathLike)):
        return read_image(os.fspath(source))
    if hasattr(source, "affine") and hasattr(source, "dataobj"):  # nibabel
        return Image(np.asanyarray(source.dataobj), np.asarray(source.affine, dtype=float))
    if affine is None:
        raise ValueError("image: an array needs affine= (4 x 4 voxel -> world mm)")
    return Image(np.asarray(source), np.asarray(affine, dtype=float))


def _optional_image(source):
    return None if source is None else image(source)


def mesh_image(source, labels=None, *, affine=None, progress=None, **options):
    """Meshes an image mask (voxels > threshold) or a closed surface (.off/.obj/.stl path) into a
    quality tet mesh, as `vpm mesh-image` does; `labels` (an atlas on the same grid) adds the
    `label` fields. `source` and `labels`: a path, a nibabel image, a vpm.Image, or an array
    with `affine`. Options: threshold, select_labels, target_vertices (5200), max_volume,
    smooth, close_at_border, radius_edge, min_dihedral. Returns (vpm.Mesh, report dict)."""
    if isinstance(source, (str, os.PathLike)) and (labels is None or isinstance(labels, (str, os.PathLike))):
        return _call(_vpm._mesh_image, progress, "mesh-image", os.fspath(source),
                     None if labels is None else os.fspath(labels), **options)
    return _call(_vpm._mesh_image, progress, "mesh-image", image(source, affine),
                 None if labels is None else image(labels, affine), **options)


def initial_map(vertices, tets=None, **options):
    """The fold-free initial map to the unit ball (paper 4.1; `vpm initial-map`). `vertices` is a
    vpm.Mesh (then no `tets`) or an (n, 3) array with `tets` (m, 4). The mesh is validated
    first (negatively oriented tets turned in place). Options: sphere ('area'|'conformal'),
    sphere_start, sphere_solve, untangle ('never'|'if-folded'|'always'), split, source, device.
    Returns (ball mesh: refined connectivity, ball positions, point field original_position;
    InitialMapReport)."""
    return _vpm._initial_map(vertices, tets, **options)


def map_to_ball(vertices, tets=None, *, progress=None, **options):
    """Maps a tet mesh to the unit ball preserving local volumes: the whole `vpm map`.

    `vertices`: a vpm.Mesh (then no `tets`) or an (n, 3) array with `tets` (m, 4). Options (as
    `vpm map`'s): rounds (-1: until tolerance), tolerance (0.01), sphere, sphere_start,
    sphere_solve, boundary, preconditioner, rk_steps, max_seconds
    (a time budget: the map reached so far, report.converged False), source (the name used in
    messages), device. `progress`: a callable given each round's line, or True for
    a tqdm bar (lines on stderr without tqdm).

    Returns (ball, report): `ball` a vpm.Mesh (input vertices first, then the inserted ones; point
    fields original_position, vertex_volume_ratio; cell field tet_volume_ratio), `report` a
    vpm.MapReport (report.final.vertex_volume_ratio.mean_abs_dev, ..., report.to_dict()).
    Raises ValueError for an input that is not a valid solid ball, vpm.NumericalError when no
    fold-free map could be made."""
    return _call(_vpm._map_to_ball, progress, "map", vertices, tets, **options)


def read_surface(path):
    """A triangle surface: (vertices (n, 3) float, faces (k, 3) int32). .off, .obj, .stl, .gii
    (GIfTI), and FreeSurfer's surfaces (lh.white, lh.pial, ...)."""
    return _vpm._read_surface(os.fspath(path))


def read_overlay(path):
    """Per-vertex values of a surface, an (n,) float array: FreeSurfer's lh.curv, lh.thickness,
    lh.sulc, or GIfTI's .shape.gii / .func.gii."""
    return _vpm._read_overlay(os.fspath(path))


def write_surface(path, vertices, faces):
    """Writes a triangle surface: .off, .obj, .stl, .gii, .vtp, or FreeSurfer's format under its names
    (.white, .pial, .sphere, ...)."""
    _vpm._write_surface(os.fspath(path), vertices, faces)


def map_to_sphere(vertices, faces, *, progress=None, **options):
    """Maps a closed genus-0 triangle surface to the unit sphere preserving local areas: `vpm map
    SURFACE`. `vertices` (n, 3), `faces` (k, 3). Options (as `vpm map`'s): rounds (polish steps,
    200), tolerance (face area mean |r-1|, 0.005), sphere ('area'|'conformal'), sphere_start,
    max_seconds, source (the name used in messages). `progress` as map_to_ball's.

    Returns (sphere, report): `sphere` an (n, 3) array of unit vectors (the input's rows), `report`
    a vpm.SurfaceMapReport (report.final.face_area_ratio.mean_abs_dev, ..., report.to_dict()).
    Raises ValueError for a surface that is not one closed, manifold, genus-0 surface."""
    return _call(_vpm._map_to_sphere, progress, "map", vertices, faces, **options)


def map_to_disk(vertices, faces, *, progress=None, **options):
    """Maps a disk-like triangle surface (one boundary loop, no handles) to the unit disk in the
    plane z = 0 preserving local areas: `vpm map` of such a surface. Options as map_to_sphere's
    (rounds, tolerance, max_seconds, source). Returns (points (n + a, 3) with z = 0, the boundary
    loop on the unit circle; vpm.SurfaceMapReport). Faces whose three corners are on the boundary
    loop ("ears", which cannot keep their area on the circle) are split first, one interior edge
    halved each: the points then have a row per added vertex after the input's n, and
    report.faces are their faces (report.added: each added vertex's edge)."""
    return _call(_vpm._map_to_sphere, progress, "map", vertices, faces, disk=True, **options)


def register_on_sphere(vertices, faces, landmarks=None, targets=None, *, values=None, template=None, **options):
    """Registers a surface mapped to the unit sphere (map_to_sphere's points) by moving
    `landmarks` onto `targets` ((L, 3) points on the sphere) with a surface-divergence-free flow,
    the face areas then restored: `vpm register SPHERE`. Either may also be (L,) vertex ids of
    `vertices` (their positions). With `values` (the subject's per-vertex scalar, for example
    curvature) and `template` ((vertices, faces, values) of a template mapped to the sphere), dense
    iterations pull the subject's scalar onto the template's (landmarks then optional).
    Options: steps (RK4 steps, 32), width_factor (0: chosen by leave-one-out), rigid (True: the
    best rotation first), restore (True), iterations (dense Gauss-Newton steps per level, 8),
    widths (the dense levels' Gaussian widths, coarse first), device (where the flows' advections
    run: a vpm.devices() index or "host"; default the module's device).

    Returns (points, report): (n, 3) unit vectors (the input's rows) and a vpm.SurfaceMapReport
    whose `initial` holds the metrics after the flow and `final` after the restoration (against
    the input sphere); report.to_dict() holds landmark_rms_error and landmark_max_error."""
    vertices = np.asarray(vertices, dtype=np.float64)
    if landmarks is None and targets is None:
        landmarks = targets = np.zeros((0, 3))
    landmarks, targets = (_vertex_rows(vertices, a, name) for a, name in ((landmarks, "landmarks"), (targets, "targets")))
    return _vpm._register_on_sphere(vertices, faces, landmarks, targets, values=values, template=template, **options)


def register_in_disk(vertices, faces, landmarks=None, targets=None, *, values=None, template=None, **options):
    """Registers a surface mapped to the unit disk (map_to_disk's points) by moving `landmarks`
    onto `targets` ((L, 3) points with z = 0 strictly inside the disk, or (L,) vertex ids) with a
    divergence-free flow tangent to the circle, the face areas then restored: `vpm register DISK`.
    With `values` and `template` ((vertices, faces, values) of a template mapped to the disk),
    dense iterations pull the subject's scalar onto the template's (landmarks then optional).
    Options as register_on_sphere's (steps, width_factor, rigid, restore, iterations, widths,
    device). Returns (points, report) as register_on_sphere."""
    vertices = np.asarray(vertices, dtype=np.float64)
    if landmarks is None and targets is None:
        landmarks = targets = np.zeros((0, 3))
    landmarks, targets = (_vertex_rows(vertices, a, name) for a, name in ((landmarks, "landmarks"), (targets, "targets")))
    return _vpm._register_in_disk(vertices, faces, landmarks, targets, values=values, template=template, **options)


def _vertex_rows(vertices, a, name):
    """(L,) integer vertex ids -> their rows of `vertices`; points as they are."""
    a = np.asarray(a)
    if a.ndim == 1 and np.issubdtype(a.dtype, np.integer):
        if a.size and (a.min() < 0 or a.max() >= len(vertices)):
            raise ValueError(f"{name}: vertex id out of range 0..{len(vertices) - 1}")
        return vertices[a]
    return a


def mean_curvature(vertices, faces):
    """Signed mean curvature at each vertex of an oriented surface ((n,), inverse length units;
    positive where it bends away from its normals): the scalar a dense registration on the
    sphere can match when FreeSurfer's curvature or sulcal depth is not at hand."""
    return _vpm._mean_curvature(np.asarray(vertices, dtype=np.float64), faces)


def locate_on_sphere(vertices, faces, points):
    """Where directions lie on a triangulation of the unit sphere (a sphere map): for each of
    `points` ((k, 3)) the face whose cone from the centre holds it and its barycentric
    coordinates there. Returns (faces (k,), bary (k, 3)); for resampling per-vertex values of one
    sphere map at another's vertices: (values[faces_array[face]] * bary).sum(1)."""
    return _vpm._locate_on_sphere(vertices, faces, points)


def register(mesh, *, landmarks=None, targets=None, template=None, image=None, template_image=None, progress=None,
             **options):
    """Registers a mapped mesh inside the ball (paper 5; `vpm register`).

    Either `landmarks` and `targets` ((N, 3) ball coordinates or (N,) vertex ids of `mesh`), or a
    mapped `template` mesh: landmarks are then the centroids of the atlas regions both carry
    (template_landmarks='regions', the default), or, for a subject without atlas labels, points
    paired by the affine that matches the two native solids' moments (template_landmarks=
    'moments'; use dense_force='image'). Dense iterations (preset='standard' for 12, 'accurate'
    for 32 to a finer width, 'landmarks' for none; or dense_iterations=N, which overrides the
    preset's; dense_force='labels'|'image'|'both') pull the subject onto the template; the image force
    reads `image` and `template_image` (path, nibabel image, vpm.Image) through both maps;
    dense_refine=N (with an image force) ends them with the image refinement, N L-BFGS iterations
    at most (300 in docs/register.md's measurements).
    Other options: exclude_labels, rk_steps, width, width_factor, flow_boundary, field, rigid,
    untangle, restore, max_seconds (a time budget for the dense iterations), device; `progress`
    as map_to_ball's (one line per dense iteration). Returns (registered vpm.Mesh,
    vpm.RegistrationReport)."""
    return _call(_vpm._register, progress, "register", mesh, landmarks=landmarks, targets=targets, template=template,
                 image=_optional_image(image), template_image=_optional_image(template_image), **options)


def elements(level=3, shells=8, samples=64, layout="shells"):
    """The canonical volume elements (paper 6.2): level-L icosphere x K shells (layout 'shells')
    or near-cubic elements (layout 'graded', K from L), S samples each."""
    return Elements(level=level, shells=shells, samples=samples, layout=layout)


def sample(mesh, images=None, labels=None, *, elements=None, subject=""):
    """Per-element features of one subject (`vpm sample`): each element's samples pulled back
    through the registered `mesh` into native space and read in `images` ({name: path, nibabel
    image, vpm.Image}; trilinear) and `labels` (fractions per label). Returns a vpm.ElementTable."""
    named = {k: image(v) for k, v in (images or {}).items()}
    return _vpm._sample(mesh, named, _optional_image(labels), elements, subject)


@dataclass
class Comparison:
    """A patient against the normals (`vpm compare`): per-element arrays and the foci."""
    z: np.ndarray
    patient: np.ndarray
    cluster: np.ndarray
    reference_mean: np.ndarray
    reference_std: np.ndarray
    clusters: list = field(default_factory=list)
    threshold_used: float = 0.0
    summary: dict = field(default_factory=dict)

    def to_dict(self):
        """The comparison's JSON (as the library writes it) with the arrays as lists."""
        d = dict(self.summary)
        for k in ("z", "patient", "cluster", "reference_mean", "reference_std"):
            d[k] = getattr(self, k).tolist()
        return d


def _json_document(what, value):
    """(JSON text, its name in messages) of a dict or of the JSON file at a path."""
    if isinstance(value, (str, os.PathLike)):
        try:
            with open(value, encoding="utf-8") as f:
                return f.read(), os.fspath(value)
        except OSError as e:
            raise ValueError(f"{what}: {os.fspath(value)}: {e.strerror}") from None
    if isinstance(value, dict):
        return json.dumps(value), what
    raise ValueError(f"{what}: expected a dict (vpm.calibrate's) or the path of a JSON file (vpm calibrate -o)")


def calibrate(normals, feature, *, rate=1.0, peak=0.0, tfce=False, **options):
    """The foci rule set by the normals themselves (`vpm calibrate`): each normal (at least 4;
    ElementTables or paths) compared in turn with the others, with compare's `options` (all but
    min_cluster), shows only false clusters; the calibration is the smallest min_cluster that
    keeps them at or under `rate` per 10 normals. peak='auto' also sets the peak rule's level
    (a smaller cluster is a focus when its peak |z| is stronger than the normals' false ones);
    tfce=True the threshold-free cluster enhancement level at which at most `rate` normals in 10
    show a focus (a family-wise rate per subject). Returns the calibration as `vpm calibrate -o`
    writes it (a dict: min_cluster, peak, tfce_level, the curve, each normal's largest and
    strongest cluster, ...); pass it to compare(calibration=...). The workflow's foci are
    compare(extend=2.25, relative_extent=0.22) calibrated with peak='auto', rate=1
    (docs/cohort.md). vpm.NumericalError when no cluster size holds the rate."""
    if "min_cluster" in options:
        raise ValueError("min_cluster: not taken (it is what calibrate finds)")
    if isinstance(peak, str):
        if peak != "auto":
            raise ValueError(f"peak: '{peak}' is neither a level nor 'auto'")
        peak = -1.0
    elif peak < 0:
        raise ValueError("peak: must be >= 0 (0: off) or 'auto'")
    _list_option(options, "covariates")
    return _vpm._calibrate(list(normals), feature, rate=rate, peak=peak, tfce=tfce, **options)


def _list_option(options, name):
    if options.get(name) is None:
        options.pop(name, None)
    else:
        options[name] = list(options[name])


def compare(normals, patient, feature, *, calibration=None, **options):
    """Compares a patient's table with the normals' (`vpm compare`): proportional scaling, the
    normals' per-element mean and std, z and foci. `normals`: ElementTables or paths; options:
    normalisation, threshold (3), fdr, min_cluster (3), extend (0; the workflow uses 2.25),
    relative_extent (0; the workflow uses 0.22), peak, sign, test, smooth, shrink (0),
    covariates (column names, e.g. ["age", "sex"]) with participants (the table that holds them,
    each table looked up by its subject): the reference then models them and reference_mean is
    the patient's prediction; image_covariate (another feature of the tables, e.g. "t1w"): each
    element's model gains the subjects' own value of it there; tfce_level (> 0: threshold-free
    cluster enhancement decides the foci, `vpm compare --tfce-level`; each cluster then has
    peak_tfce). calibration (vpm.calibrate's dict or the path of `vpm calibrate -o`'s file, made
    on the same normals with the same options; `vpm compare --min-cluster-from`) sets min_cluster,
    the peak level or the TFCE level, and gives each focus its family-wise p-value (p_family).
    Returns a Comparison."""
    _list_option(options, "covariates")
    if calibration is not None:
        taken = [k for k in ("min_cluster",) if k in options]
        if taken:
            raise ValueError(f"{taken[0]}: the calibration sets it (give one or the other)")
        options["calibration"], options["calibration_source"] = _json_document("calibration", calibration)
    d = _vpm._compare(list(normals), patient, feature, **options)
    arrays = {k: d.pop(k) for k in ("z", "patient", "cluster", "reference_mean", "reference_std")}
    return Comparison(**arrays, clusters=d.get("clusters", []), threshold_used=d.get("threshold", 0.0),
                      summary=d)
