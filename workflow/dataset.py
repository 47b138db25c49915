"""The cohort workflow's subjects, read from a dataset the user did not make (docs/robustness.md).

A dataset's participant ids, groups and file names come from elsewhere. Nothing read here is
ever executed: every path the workflow passes to a shell command is quoted by the Snakefile
(Snakemake's `:q`), and this module refuses, with one line naming the file, what quoting cannot
carry:

* characters Snakemake itself reads in a path (`{` and `}`: it takes them for wildcards and
  stops the whole workflow with an error that names no file),
* `,` (vpm's list options such as `--images pet=A,t1w=B` split on it),
* control characters (a newline ends a shell command line) and names that are not UTF-8,
* in a BIDS dataset, files or subject folders that resolve (through symbolic links) outside
  the dataset,
* participant ids that are not `sub-<letters and digits>` (at most 64 characters), duplicate
  ids, and groups outside letters, digits, `_`, `-`, `.` (at most 64 characters).

Everything else (spaces, quotes, `$`, `;`, backticks, parentheses, unicode letters, long names
up to the file system's limit) is accepted and reaches `vpm` as one quoted argument.

Used by workflow/Snakefile; tested by tests/workflow/test_dataset.py and tests/workflow/hostile.sh.
"""
import csv
import glob
import os
import re

SUBJECT_ID = re.compile(r"sub-[A-Za-z0-9]{1,60}")
GROUP = re.compile(r"[A-Za-z0-9_.-]{1,64}")
# what quoting cannot carry through Snakemake and vpm's list options
UNSAFE = re.compile(r"[{},\x00-\x1f\x7f]")


class DatasetError(Exception):
    """A dataset the workflow refuses; the message is one line naming the file and the problem."""


def check_path(path, root=None, what="file"):
    """`path` if the workflow can pass it to a command safely, else DatasetError. With `root`,
    the path must also resolve (symbolic links followed) inside that folder."""
    try:
        path.encode("utf-8")
    except UnicodeEncodeError:
        raise DatasetError(f"{ascii(path)}: {what}: the name is not UTF-8") from None
    bad = UNSAFE.search(path)
    if bad:
        raise DatasetError(f"{ascii(path)}: {what}: the name holds {ascii(bad.group())}, which the workflow refuses "
                           "(braces, commas and control characters cannot be passed on safely); rename it")
    if root is not None:
        real, top = os.path.realpath(path), os.path.realpath(root)
        if os.path.commonpath([real, top]) != top:
            raise DatasetError(f"{path}: {what}: resolves to {real}, outside the dataset {top}; "
                               "copy the file into the dataset instead of linking to it")
    return path


def read_participants(path):
    """Rows of a participants table (TSV with participant_id and group), every id and group
    checked; DatasetError names the file and line of the first bad one."""
    if not os.path.isfile(path):
        raise DatasetError(f"{path}: not found")
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f, delimiter="\t"))
    except (UnicodeDecodeError, csv.Error) as e:
        raise DatasetError(f"{path}: not a UTF-8 tab-separated table ({e})") from None
    for col in ("participant_id", "group"):
        if not rows or col not in rows[0]:
            raise DatasetError(f"{path}:1: needs a '{col}' column")
    seen = set()
    for line, row in enumerate(rows, start=2):
        sid, group = row["participant_id"] or "", row["group"] or ""
        if not SUBJECT_ID.fullmatch(sid):
            raise DatasetError(f"{path}:{line}: participant_id {ascii(sid)} is not 'sub-' and 1-60 letters or digits")
        if sid in seen:
            raise DatasetError(f"{path}:{line}: participant_id {sid} appears twice")
        seen.add(sid)
        if not GROUP.fullmatch(group):
            raise DatasetError(f"{path}:{line}: group {ascii(group)} of {sid} is not 1-64 letters, digits, '_', '-' or '.'")
        row["_line"] = line
    return rows


COVARIATE = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}")


def check_covariates(path, names, subjects):
    """The covariate columns `names` exist in the participants table at `path` (names: letters,
    digits, '_') and every one of `subjects` has a value for each (not empty, not 'n/a');
    DatasetError names the file, the line and the first problem."""
    for name in names:
        if not COVARIATE.fullmatch(name):
            raise DatasetError(f"compare.covariates: {ascii(name)} is not a column name (letters, digits, '_')")
    rows = {row["participant_id"]: row for row in read_participants(path)}
    for name in names:
        if name not in next(iter(rows.values()), {}):
            raise DatasetError(f"{path}:1: no column '{name}' (compare.covariates)")
    for sid in subjects:
        row = rows.get(sid)
        if row is None:
            raise DatasetError(f"{path}: no row for {sid} (compare.covariates)")
        for name in names:
            if (row.get(name) or "").strip() in ("", "n/a", "NA"):
                raise DatasetError(f"{path}:{row['_line']}: {sid} has no {name} (compare.covariates)")


def find_one(folder, pattern, what, root, required=True):
    """The one file matching `pattern` (a glob of file names) in `folder`, checked by
    check_path against `root`; "" when none and not required."""
    hits = sorted(glob.glob(os.path.join(glob.escape(folder), pattern)))
    if len(hits) > 1:
        raise DatasetError(f"{os.path.join(folder, pattern)}: {len(hits)} files match; expected one {what}")
    if not hits:
        if required:
            raise DatasetError(f"{os.path.join(folder, pattern)}: no {what} found")
        return ""
    return check_path(os.path.abspath(hits[0]), root, what)


def anatomy(root, sid, subject_dir):
    """A subject's anatomy: {"image": what `vpm mesh-image` meshes (voxels > 0), "t1w": the image
    the dense image force reads ("" for none), "labels": a label image ("" for none), "scheme":
    the labels' scheme ("atlas": the template's atlas, as a raw dataset's _dseg; "aseg":
    FreeSurfer's segmentation numbers; "" without labels), "source"}. Looked for, in this order:

    * fMRIPrep derivatives in native T1w space (no space- entity), derivatives/fmriprep/<sub>/anat:
      <sub>_desc-brain_mask (meshed),
      <sub>_desc-preproc_T1w (the image force), <sub>_desc-aseg_dseg (labels, optional);
    * FreeSurfer, derivatives/freesurfer/<sub>/mri: brainmask.mgz (the skull-stripped T1: meshed
      and the image force), aparc+aseg.mgz or aseg.mgz (labels, optional);
    * the raw dataset, <sub>/anat: <sub>*_T1w (or a brain mask <sub>*_mask, which has no
      intensities for the image force), <sub>*_dseg (atlas labels, optional).
    """
    fmriprep = os.path.join(root, "derivatives", "fmriprep", sid, "anat")
    freesurfer = os.path.join(root, "derivatives", "freesurfer", sid, "mri")
    if os.path.isdir(fmriprep):
        check_path(fmriprep, root, "fMRIPrep anat folder")
        labels = find_one(fmriprep, f"{sid}_desc-aseg_dseg.nii*", "fMRIPrep aseg (desc-aseg_dseg)", root, required=False)
        return {"image": find_one(fmriprep, f"{sid}_desc-brain_mask.nii*", "fMRIPrep brain mask (desc-brain_mask)", root),
                "t1w": find_one(fmriprep, f"{sid}_desc-preproc_T1w.nii*", "fMRIPrep T1w (desc-preproc_T1w)", root,
                                required=False),
                "labels": labels, "scheme": "aseg" if labels else "", "source": "fmriprep"}
    if os.path.isdir(freesurfer):
        check_path(freesurfer, root, "FreeSurfer mri folder")
        brain = find_one(freesurfer, "brainmask.mgz", "FreeSurfer brainmask.mgz", root)
        labels = find_one(freesurfer, "aparc+aseg.mgz", "FreeSurfer aparc+aseg.mgz", root, required=False) or \
            find_one(freesurfer, "aseg.mgz", "FreeSurfer aseg.mgz", root, required=False)
        return {"image": brain, "t1w": brain, "labels": labels, "scheme": "aseg" if labels else "",
                "source": "freesurfer"}
    anat = os.path.join(subject_dir, "anat")
    t1w = find_one(anat, f"{sid}*_T1w.nii*", "T1w image", root, required=False)
    image = t1w or find_one(anat, f"{sid}*_mask.nii*", "T1w image or brain mask", root)
    labels = find_one(anat, f"{sid}*_dseg.nii*", "atlas labels (_dseg)", root, required=False)
    return {"image": image, "t1w": t1w, "labels": labels, "scheme": "atlas" if labels else "", "source": "bids"}


def subjects_from_bids(root, feature, more):
    """{participant_id: {"group", "image", "t1w", "labels", "scheme", "source", feature, *more}}
    from a BIDS dataset: participants.tsv, each subject's anatomy (see anatomy(): fMRIPrep or
    FreeSurfer derivatives, or the raw anat/ folder) and <feature>/<sub>*_<feature> images.
    `more`: name -> "folder/suffix" of further images."""
    root = os.path.abspath(root)
    check_path(root, what="dataset folder")
    table = os.path.join(root, "participants.tsv")
    subs = {}
    for row in read_participants(table):
        sid = row["participant_id"]
        d = os.path.join(root, sid)
        if not os.path.isdir(d):
            raise DatasetError(f"{table}:{row['_line']}: {sid}: no folder {d}")
        check_path(d, root, "subject folder")
        subs[sid] = {"group": row["group"], **anatomy(root, sid, d), "surface": "", "overlay": "",
                     feature: find_one(os.path.join(d, feature), f"{sid}*_{feature}.nii*", f"{feature} image", root)}
        for name, spec in more.items():
            folder, _, suffix = spec.partition("/")
            if not suffix:
                raise DatasetError(f"more_features: {name}: '{spec}' is not folder/suffix (e.g. anat/T1w)")
            subs[sid][name] = find_one(os.path.join(d, folder), f"{sid}*_{suffix}.nii*", f"{name} image", root)
    return subs


def subjects_from_table(path, features):
    """The same from a TSV with participant_id, group, image, labels and one column per feature
    (paths relative to the table; they may point anywhere the user can read, but must exist and
    pass check_path); with a `surface` column (and `overlay`), each subject's surface and its
    per-vertex scalar (add_surfaces_from_bids's keys)."""
    base = os.path.dirname(os.path.abspath(path))
    subs = {}
    rows = read_participants(path)
    surface_cols = [c for c in ("surface", "overlay") if c in rows[0]]
    if surface_cols == ["overlay"]:
        raise DatasetError(f"{path}:1: an 'overlay' column without a 'surface' column")
    for row in rows:
        sid, line = row["participant_id"], row["_line"]
        entry = {"group": row["group"], "surface": "", "overlay": ""}
        for col in ("image", "labels", *features, *surface_cols):
            if not row.get(col):
                raise DatasetError(f"{path}:{line}: no '{col}' for {sid}")
            p = os.path.join(base, row[col])
            check_path(p, what=f"{col} of {sid} ({path}:{line})")
            if not os.path.isfile(p):
                raise DatasetError(f"{path}:{line}: {col} of {sid}: {p} not found")
            entry[col] = p
        entry["t1w"] = "" if "_mask.nii" in os.path.basename(entry["image"]) else entry["image"]
        entry.update(scheme="atlas", source="table")
        subs[sid] = entry
    return subs


def add_surfaces_from_bids(subjects, root, name, overlay):
    """Each subject's surface, derivatives/freesurfer/<sub>/surf/<name> (any surface vpm reads:
    FreeSurfer's lh.white, a GIfTI, ...), and with `overlay` its per-vertex scalar beside it (e.g.
    lh.sulc), as subjects[sid]["surface"] and ["overlay"] ("" for none). Every subject must have
    them; `name` and `overlay` are file names, not paths."""
    for n, what in ((name, "surfaces.name"), (overlay, "surfaces.overlay")):
        if n and ("/" in n or os.sep in n or n in (".", "..")):
            raise DatasetError(f"{what}: '{n}' is not a file name (a file in derivatives/freesurfer/<sub>/surf/)")
        if n:
            check_path(n, what=what)
    root = os.path.abspath(root)
    for sid, entry in subjects.items():
        surf = os.path.join(root, "derivatives", "freesurfer", sid, "surf")
        entry["surface"] = find_one(surf, glob.escape(name), f"surface {name}", root)
        entry["overlay"] = find_one(surf, glob.escape(overlay), f"overlay {overlay}", root) if overlay else ""
    return subjects
