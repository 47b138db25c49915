# Surfaces (docs/cohort.md "Surfaces", docs/surfaces.md), included by workflow/Snakefile: each
# subject's surface (a FreeSurfer lh.white, a GIfTI, ...) mapped to the unit sphere by `vpm map`,
# area-preserving; with surfaces.template, registered onto the template surface's sphere by
# `vpm register SPHERE --template --overlay --template-overlay`, its per-vertex scalar (e.g.
# lh.sulc) pulled onto the template's. Target `surfaces` (part of `participant` and `group` when
# the subjects have surfaces); off while no subject has one.
SURFACE_SUBJECTS = sorted(s for s, v in SUBJECTS.items() if v.get("surface"))
SURF_TEMPLATE = str(SURF.get("template") or "")
SURF_TEMPLATE_OVERLAY = str(SURF.get("template_overlay") or "")
try:
    for _path, _what in ((SURF_TEMPLATE, "surfaces.template"), (SURF_TEMPLATE_OVERLAY, "surfaces.template_overlay")):
        if _path:
            dataset.check_path(_path, what=_what)
            if not os.path.isfile(_path):
                fail(f"{_what}: {_path} not found")
except dataset.DatasetError as e:
    fail(str(e))
if SURF_TEMPLATE and SURFACE_SUBJECTS:
    if not SURF_TEMPLATE_OVERLAY:
        fail("surfaces.template: the registration matches a per-vertex scalar; set surfaces.template_overlay "
             "(the template's, e.g. its lh.sulc)")
    _without = [s for s in SURFACE_SUBJECTS if not SUBJECTS[s]["overlay"]]
    if _without:
        fail(f"surfaces.template: {_without[0]} has no overlay (the scalar matched to the template's); "
             "set surfaces.overlay (BIDS) or an overlay column (subjects table)")
SURFACE_OUTPUTS = (expand(OUT + "/surfaces/{sub}/{sub}_sphere.gii", sub=SURFACE_SUBJECTS)
                   + (expand(OUT + "/surfaces/{sub}/{sub}_registered.gii", sub=SURFACE_SUBJECTS) if SURF_TEMPLATE else []))


rule surfaces:
    input:
        SURFACE_OUTPUTS,


rule surface_map:
    input:
        lambda w: SUBJECTS[w.sub]["surface"],
    output:
        OUT + "/surfaces/{sub}/{sub}_sphere.gii",
    log:
        OUT + "/logs/{sub}_surface_map.log",
    benchmark:
        OUT + "/benchmarks/{sub}_surface_map.tsv"
    group:
        "participant"
    threads: 1
    resources:
        mem_mb=1500,
        runtime=10,
    params:
        report=lambda w: f"{OUT}/surfaces/{w.sub}/{w.sub}_map.json",
    shell:
        "{VPM:q} map {input:q} -o {output:q} --report {params.report:q} > {log:q} 2>&1"


rule template_surface_map:
    input:
        SURF_TEMPLATE,
    output:
        OUT + "/template/surface_sphere.gii",
    log:
        OUT + "/logs/template_surface_map.log",
    benchmark:
        OUT + "/benchmarks/template_surface_map.tsv"
    params:
        report=OUT + "/template/surface_map.json",
    shell:
        "{VPM:q} map {input:q} -o {output:q} --report {params.report:q} > {log:q} 2>&1"


rule surface_register:
    input:
        sphere=OUT + "/surfaces/{sub}/{sub}_sphere.gii",
        template=OUT + "/template/surface_sphere.gii",
        overlay=lambda w: SUBJECTS[w.sub]["overlay"],
        template_overlay=SURF_TEMPLATE_OVERLAY,
    output:
        OUT + "/surfaces/{sub}/{sub}_registered.gii",
    log:
        OUT + "/logs/{sub}_surface_register.log",
    benchmark:
        OUT + "/benchmarks/{sub}_surface_register.tsv"
    group:
        "participant"
    threads: 1
    resources:
        mem_mb=1500,
        runtime=10,
    params:
        extra=shlex.split(str(SURF.get("register_extra") or "")),
        report=lambda w: f"{OUT}/surfaces/{w.sub}/{w.sub}_register.json",
    shell:
        "{VPM:q} register {input.sphere:q} -o {output:q} --template {input.template:q} --overlay {input.overlay:q} "
        "--template-overlay {input.template_overlay:q} {params.extra:q} --report {params.report:q} > {log:q} 2>&1"
