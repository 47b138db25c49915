"""The cohort workflow on subjects as pipelines write them: one from fMRIPrep's derivatives
(desc-brain_mask, desc-preproc_T1w, desc-aseg_dseg) and one from FreeSurfer's (brainmask.mgz,
aparc+aseg.mgz), beside raw BIDS subjects, run to the group level. Their aseg labels are not in
the template's (AAL) scheme, so they are registered by the moments' affine and the image force."""
import json
import os
import shutil
import subprocess

import nibabel as nib
import numpy as np
import pytest

from conftest import BUILD, SOURCE


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    work = tmp_path_factory.mktemp("pipelines")
    bids = work / "bids"
    # a copy of the synthetic cohort ctest's workflow:cohort made (VPM_TEST_COHORT_BIDS, 3 normals
    # and a patient), else one made here
    made = os.environ.get("VPM_TEST_COHORT_BIDS", "")
    if made and os.path.exists(os.path.join(made, "participants.tsv")):
        shutil.copytree(made, bids)
    else:
        subprocess.run(["/usr/bin/python3", f"{SOURCE}/scripts/synth_cohort.py", "--out", str(bids), "--normals", "3",
                        "--patients", "1", "--seed", "7", "--jobs", "2"], check=True, capture_output=True)
    # sub-N02 as fMRIPrep writes it (native T1w space), its raw anat/ gone
    anat = bids / "sub-N02" / "anat"
    fp = bids / "derivatives" / "fmriprep" / "sub-N02" / "anat"
    fp.mkdir(parents=True)
    t1 = nib.load(str(anat / "sub-N02_T1w.nii.gz"))
    nib.save(t1, str(fp / "sub-N02_desc-preproc_T1w.nii.gz"))
    mask = (np.asanyarray(t1.dataobj) > 0).astype(np.uint8)
    nib.save(nib.Nifti1Image(mask, t1.affine), str(fp / "sub-N02_desc-brain_mask.nii.gz"))
    shutil.copy(anat / "sub-N02_dseg.nii.gz", fp / "sub-N02_desc-aseg_dseg.nii.gz")
    shutil.rmtree(anat)
    # sub-N03 as FreeSurfer writes it: .mgz volumes
    anat = bids / "sub-N03" / "anat"
    fs = bids / "derivatives" / "freesurfer" / "sub-N03" / "mri"
    fs.mkdir(parents=True)
    t1 = nib.load(str(anat / "sub-N03_T1w.nii.gz"))
    nib.save(nib.MGHImage(np.asanyarray(t1.dataobj).astype(np.uint8 if t1.get_data_dtype().kind == "u" else np.int16),
                          t1.affine), str(fs / "brainmask.mgz"))
    seg = nib.load(str(anat / "sub-N03_dseg.nii.gz"))
    nib.save(nib.MGHImage(np.asanyarray(seg.dataobj).astype(np.int32), seg.affine), str(fs / "aparc+aseg.mgz"))
    shutil.rmtree(anat)
    # the evaluation against planted truth reads every subject's raw AAL _dseg (a synthetic
    # cohort's baseline), which these subjects no longer have: not part of this test
    shutil.rmtree(bids / "derivatives" / "truth")
    (work / "fast.yaml").write_text("mesh: {target_vertices: 2000}\nview: {enabled: false}\n"
                                    "elements: {layout: graded, level: 3, samples: 16}\n")
    return work


def snakemake(work, *args):
    cmd = ["snakemake", "-s", f"{SOURCE}/workflow/Snakefile", "--cores", "2", "--configfile",
           f"{SOURCE}/workflow/config.yaml", str(work / "fast.yaml"), "--config", f"bids={work / 'bids'}",
           f"out={work / 'results'}", f"vpm={BUILD}/vpm", *args]
    return subprocess.run(cmd, cwd=work, capture_output=True, text=True,
                          env=dict(os.environ, POCL_CACHE_DIR=os.path.join(BUILD, "pocl-cache")))


def test_fmriprep_and_freesurfer_subjects_through_the_workflow(dataset):
    plan = snakemake(dataset, "-n", "-p")
    assert plan.returncode == 0, plan.stdout + plan.stderr
    lines = plan.stdout.splitlines()
    mesh = {s: next(l for l in lines if "mesh-image" in l and f"{s}_mesh.vtu" in l) for s in ("sub-N01", "sub-N02", "sub-N03")}
    assert "sub-N02_desc-brain_mask.nii.gz" in mesh["sub-N02"] and "desc-aseg_dseg" in mesh["sub-N02"]
    assert "brainmask.mgz" in mesh["sub-N03"] and "aparc+aseg.mgz" in mesh["sub-N03"]
    reg = {s: next(l for l in lines if " register " in l and f"{s}_ball.vtu" in l) for s in ("sub-N01", "sub-N02", "sub-N03")}
    assert "--template-landmarks moments" in reg["sub-N02"] and "--dense-force image" in reg["sub-N02"]
    assert "sub-N02_desc-preproc_T1w.nii.gz" in reg["sub-N02"]
    assert "--template-landmarks moments" in reg["sub-N03"] and "brainmask.mgz" in reg["sub-N03"]
    assert "moments" not in reg["sub-N01"] and "--dense-force image" in reg["sub-N01"]

    run = snakemake(dataset)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    r = dataset / "results"
    for s in ("sub-N01", "sub-N02", "sub-N03", "sub-P01"):
        assert (r / "tables" / f"{s}_pet.h5").stat().st_size > 0
    assert (r / "compare" / "sub-P01_pet_z.nii.gz").stat().st_size > 0
    for s, source in (("sub-N02", "fMRIPrep"), ("sub-N03", "FreeSurfer")):
        rep = json.load(open(r / "subjects" / s / f"{s}_register.json"))
        assert rep["dense"]["force"] == "image", source
        assert rep["input"]["landmarks"] >= 20 and rep["inverted_tets"] == 0, source
        assert rep["dense"]["mismatch_after"] < rep["dense"]["mismatch_before"], source


def uv_sphere(rings, per):
    """A unit sphere triangulated by `rings` circles of latitude of `per` vertices and two poles."""
    t = np.linspace(0, np.pi, rings + 2)[1:-1]
    p = np.linspace(0, 2 * np.pi, per, endpoint=False)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    pts = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], -1).reshape(-1, 3)
    pts = np.vstack([[0, 0, 1], pts, [0, 0, -1]])
    idx = lambda r, k: 1 + r * per + k % per  # noqa: E731
    faces = []
    for k in range(per):
        faces += [[0, idx(0, k), idx(0, k + 1)], [len(pts) - 1, idx(rings - 1, k + 1), idx(rings - 1, k)]]
        for r in range(rings - 1):
            faces += [[idx(r, k), idx(r + 1, k), idx(r + 1, k + 1)], [idx(r, k), idx(r + 1, k + 1), idx(r, k + 1)]]
    return pts, np.array(faces)


def feature(x):
    """A smooth scalar with features in every direction (the surfaces' "sulc")."""
    return (np.sin(3 * x[:, 0] + x[:, 2] + 0.2) + 0.8 * np.sin(4 * x[:, 1] - 2 * x[:, 2] + 1.1)
            + 0.7 * np.sin(-2 * x[:, 0] + x[:, 1] + 5 * x[:, 2] + 2.3))


def twist(x, angle):
    """Each circle of latitude about the z axis turned by an angle that varies with its height
    (areas kept)."""
    a = angle * np.sin(np.pi * (x[:, 2] + 1) / 2)
    c, s = np.cos(a), np.sin(a)
    return np.stack([c * x[:, 0] - s * x[:, 1], s * x[:, 0] + c * x[:, 1], x[:, 2]], -1)


def test_surfaces_through_the_workflow(dataset, vpm):
    """Each subject's FreeSurfer surface (derivatives/freesurfer/<sub>/surf/lh.white, lh.sulc)
    mapped to the sphere and registered onto a template surface's sphere by its scalar: the
    subjects' scalars are the template's twisted, so the registration must raise the correlation."""
    bumpy = lambda p: p * [1.6, 1.0, 0.8] * (1 + 0.3 * np.exp(-np.sum((p - [0.6, 0, 0.8]) ** 2, 1) / 0.2))[:, None]  # noqa: E731
    subjects = ("sub-N01", "sub-N02", "sub-N03", "sub-P01")
    for k, sid in enumerate(subjects):
        surf = dataset / "bids" / "derivatives" / "freesurfer" / sid / "surf"
        surf.mkdir(parents=True, exist_ok=True)
        p, f = uv_sphere(18, 36)
        vpm.write_surface(surf / "lh.white", bumpy(p), f)
        nib.freesurfer.write_morph_data(str(surf / "lh.sulc"), feature(twist(p, 0.15 + 0.05 * k)).astype(np.float32))
    q, g = uv_sphere(30, 60)  # the template: another triangulation of the same anatomy
    vpm.write_surface(dataset / "template.white", bumpy(q), g)
    nib.freesurfer.write_morph_data(str(dataset / "template.sulc"), feature(q).astype(np.float32))
    (dataset / "surfaces.yaml").write_text(
        f"surfaces: {{name: lh.white, overlay: lh.sulc, template: '{dataset / 'template.white'}', "
        f"template_overlay: '{dataset / 'template.sulc'}'}}\n")
    run = lambda *a: subprocess.run(  # noqa: E731
        ["snakemake", *a, "-s", f"{SOURCE}/workflow/Snakefile", "--cores", "2", "--configfile", f"{SOURCE}/workflow/config.yaml",
         str(dataset / "fast.yaml"), str(dataset / "surfaces.yaml"), "--config", f"bids={dataset / 'bids'}",
         f"out={dataset / 'surface_results'}", f"vpm={BUILD}/vpm"],
        cwd=dataset, capture_output=True, text=True, env=dict(os.environ, POCL_CACHE_DIR=os.path.join(BUILD, "pocl-cache")))
    done = run("surfaces")
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    r = dataset / "surface_results"
    for sid in subjects:
        m = json.load(open(r / "surfaces" / sid / f"{sid}_map.json"))
        assert m["final"]["face_area_ratio"]["mean_abs_dev"] <= 0.005 and m["final"]["flipped_faces"] == 0, m["final"]
        g = json.load(open(r / "surfaces" / sid / f"{sid}_register.json"))["registration"]
        before, after = g["match"]["correlation_before"], g["match"]["correlation_after"]
        assert after > 0.99 and 1 - after < 0.2 * (1 - before), (sid, g["match"])
        assert g["final"]["flipped_faces"] == 0 and g["final"]["face_area_ratio"]["mean_abs_dev"] <= 0.005, (sid, g["final"])
        pts, faces = vpm.read_surface(r / "surfaces" / sid / f"{sid}_registered.gii")
        assert np.allclose(np.linalg.norm(pts, axis=1), 1, atol=1e-6) and len(faces) == 2 * 36 * 18
    again = run("surfaces", "-n")
    assert again.returncode == 0 and "Nothing to be done" in again.stdout + again.stderr, again.stdout[-2000:]
    # a template without its scalar is refused before any job, naming the setting
    (dataset / "surfaces.yaml").write_text(f"surfaces: {{name: lh.white, overlay: lh.sulc, template: '{dataset / 'template.white'}'}}\n")
    bad = run("surfaces", "-n")
    assert bad.returncode != 0 and "surfaces.template_overlay" in bad.stdout + bad.stderr


def test_dataset_surfaces_from_a_table_and_from_bids(tmp_path):
    """workflow/dataset.py: a subjects table's surface and overlay columns, a BIDS dataset's
    derivatives/freesurfer/<sub>/surf/ files, and what either refuses with one line."""
    import sys
    sys.path.insert(0, f"{SOURCE}/workflow")
    import dataset as ds
    for name in ("a.nii", "b.nii", "pet.nii", "lh.white", "lh.sulc"):
        (tmp_path / name).write_bytes(b"x")
    head = "participant_id\tgroup\timage\tlabels\tpet"
    row = "sub-A\tnormal\ta.nii\tb.nii\tpet.nii"
    (tmp_path / "t.tsv").write_text(f"{head}\tsurface\toverlay\n{row}\tlh.white\tlh.sulc\n")
    s = ds.subjects_from_table(str(tmp_path / "t.tsv"), ["pet"])["sub-A"]
    assert s["surface"] == str(tmp_path / "lh.white") and s["overlay"] == str(tmp_path / "lh.sulc")
    (tmp_path / "t.tsv").write_text(f"{head}\n{row}\n")  # no surface column: none
    assert ds.subjects_from_table(str(tmp_path / "t.tsv"), ["pet"])["sub-A"]["surface"] == ""
    for table, message in ((f"{head}\toverlay\n{row}\tlh.sulc\n", "an 'overlay' column without a 'surface' column"),
                           (f"{head}\tsurface\n{row}\tlh.pial\n", "t.tsv:2: surface of sub-A"),
                           (f"{head}\tsurface\n{row}\t\n", "t.tsv:2: no 'surface' for sub-A")):
        (tmp_path / "t.tsv").write_text(table)
        with pytest.raises(ds.DatasetError, match=message):
            ds.subjects_from_table(str(tmp_path / "t.tsv"), ["pet"])
    surf = tmp_path / "bids" / "derivatives" / "freesurfer" / "sub-A" / "surf"
    surf.mkdir(parents=True)
    (surf / "lh.white").write_bytes(b"x")
    subs = {"sub-A": {}}
    ds.add_surfaces_from_bids(subs, str(tmp_path / "bids"), "lh.white", "")
    assert subs["sub-A"] == {"surface": str(surf / "lh.white"), "overlay": ""}
    with pytest.raises(ds.DatasetError, match="no overlay lh.sulc found"):
        ds.add_surfaces_from_bids(subs, str(tmp_path / "bids"), "lh.white", "lh.sulc")
    for bad, message in (("../lh.white", "not a file name"), ("lh,white", "braces, commas")):
        with pytest.raises(ds.DatasetError, match=message):
            ds.add_surfaces_from_bids(subs, str(tmp_path / "bids"), bad, "")
