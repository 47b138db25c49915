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
    assert "moments" not in reg["sub-N01"] and "--dense-force both" in reg["sub-N01"]

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
