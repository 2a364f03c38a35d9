//! The spine FE benchmark's L2 (Walle, Matheson & Boyd 2025) by the direct route: its label
//! map meshed voxel by voxel (`voxel-mesh`, bone and pads), its density image mapped with the
//! benchmark's recipe, its compression test solved by CalculiX (`materials --load --solve`),
//! with the files in `examples/spine_benchmark/`. Checked on what is delivered: the element
//! count against nibabel's voxels, the deck's sets and materials as meshio and the deck's text
//! give them, the reaction read from CalculiX's `.dat` file, and the same stiffness from the
//! same vertebra written by nibabel in another storage order (RAS, axes permuted). And by the
//! atlas route: an atlas of the shared VerSe L1 vertebrae fitted to the bone's labels, the pads
//! joined to its mesh by a tie (`voxel-mesh --join`), the same recipe integrated over the
//! smooth elements (Bonemat V3).

use crate::common;
use std::path::Path;

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// Writes the image and label map reoriented to axis codes S, R, A (nibabel's `as_reoriented`:
/// axes permuted and flipped, the affine following), and prints the label counts.
const REORIENT: &str = r#"
import sys, json
import nibabel as nib, numpy as np
im, seg, out = sys.argv[1:4]
target = nib.orientations.axcodes2ornt(("S", "R", "A"))
counts = {}
for path, name in [(im, "im"), (seg, "seg")]:
    img = nib.load(path)
    t = nib.orientations.ornt_transform(nib.orientations.io_orientation(img.affine), target)
    r = img.as_reoriented(t)
    nib.save(nib.Nifti1Image(np.asanyarray(r.dataobj), r.affine), f"{out}/{name}_SRA.nii.gz")
    if name == "seg":
        d = np.asanyarray(img.dataobj)
        counts = {str(k): int((d == k).sum()) for k in range(1, 7)}
        counts["axcodes"] = "".join(nib.aff2axcodes(r.affine))
print(json.dumps(counts))
"#;

/// Reads the deck: meshio's element sets (sizes) and, from the deck's text, each material's
/// E and its section's element set; the `.dat` file's total reaction of set TOP.
const READ_BACK: &str = r#"
import sys, json, re
import meshio
inp, dat = sys.argv[1:3]
m = meshio.read(inp)
sets = {k: int(sum(len(c) for c in v)) for k, v in m.cell_sets.items()}
point_sets = {k: len(v) for k, v in m.point_sets.items()}
text = open(inp).read()
materials = {}
for name, e, nu in re.findall(r"\*MATERIAL, NAME=(\S+)\n\*ELASTIC\n([^,\n]+), ([^\n]+)\n", text):
    materials[name] = [float(e), float(nu)]
sections = re.findall(r"\*SOLID SECTION, ELSET=(\S+), MATERIAL=(\S+)", text)
lines = open(dat).read().splitlines()
top = None
for i, l in enumerate(lines):
    if l.strip().startswith("total force (fx,fy,fz) for set TOP "):
        top = [float(v) for v in next(x for x in lines[i + 1:] if x.strip()).split()]
print(json.dumps({"sets": sets, "point_sets": point_sets, "materials": materials, "sections": sections, "top": top,
                  "nodes": len(m.points), "cells": int(sum(len(c.data) for c in m.cells))}))
"#;

/// Runs `script` with `argv` in the Python `py`; the JSON it prints.
fn python_json(py: &Path, script: &str, argv: &[String]) -> serde_json::Value {
    let o = common::run(
        std::process::Command::new(py)
            .arg("-c")
            .arg(script)
            .args(argv),
        common::deadline::PYTHON,
    );
    assert!(
        o.status.success(),
        "python: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

/// The solve's stiffness within `bound` (a share) of the recipe's 10 442 N/mm, and the
/// reactions of the displaced and the held face balanced along z.
fn assert_stiffness(solve: &atlasmesh::study::SolveReport, bound: f64) {
    let relative = solve.stiffness_n_per_mm / 10_442.0 - 1.0;
    assert!(
        relative.abs() <= bound,
        "{:.0} N/mm: {:+.1} % from the recipe's 10 442 N/mm",
        solve.stiffness_n_per_mm,
        100.0 * relative
    );
    let top = solve.reactions["TOP"];
    let bottom = solve.reactions["BOTTOM"];
    assert!(
        (top[2] + bottom[2]).abs() < 1e-6 * top[2].abs(),
        "{top:?} {bottom:?}"
    );
}

/// The model two decks hold, compared as sets: their nodes (coordinates), their elements
/// (centroid and Young's modulus), the node sets of the load case (coordinates) and the step
/// as written. Each list sorted by its values rounded to 1e-3 mm, then compared to 2e-3 mm
/// (the same point computed in another order differs in its last bits).
const SAME_MODEL: &str = r#"
import sys, json, re
import meshio, numpy as np
def model(inp):
    m = meshio.read(inp)
    text = open(inp).read()
    E = {n: float(e) for n, e in re.findall(r"\*MATERIAL, NAME=(\S+)\n\*ELASTIC\n([^,\n]+),", text)}
    cells = np.concatenate([c.data for c in m.cells])
    start = np.cumsum([0] + [len(c.data) for c in m.cells])
    modulus = np.full(len(cells), np.nan)
    for name, blocks in m.cell_sets.items():
        if name in E:
            for b, idx in enumerate(blocks):
                modulus[start[b] + np.asarray(idx, dtype=int)] = E[name]
    def rows(a):
        a = np.asarray(a, dtype=float)
        return a[np.lexsort(np.round(a, 3).T[::-1])]
    sets = {k: rows(m.points[np.asarray(v, dtype=int)]) for k, v in m.point_sets.items() if k in ("TOP", "BOTTOM")}
    return (rows(m.points), rows(np.column_stack([m.points[cells].mean(axis=1), modulus])), sets,
            text[text.index("*STEP"):])
a, b = model(sys.argv[1]), model(sys.argv[2])
same = lambda x, y: x.shape == y.shape and bool(np.allclose(x, y, rtol=0, atol=2e-3, equal_nan=False))
print(json.dumps({
  "nodes": [len(a[0]), len(b[0])], "elements": [len(a[1]), len(b[1])],
  "same_nodes": same(a[0], b[0]), "same_elements": same(a[1], b[1]),
  "unmapped": int(np.isnan(a[1][:, 3]).sum() + np.isnan(b[1][:, 3]).sum()),
  "load_sets": sorted(a[2]),
  "same_load_sets": sorted(a[2]) == sorted(b[2]) and all(same(a[2][k], b[2][k]) for k in a[2]),
  "same_step": a[3] == b[3],
}))
"#;

/// `voxel-mesh` and `materials --load` (`--solve` when `solve`) on one image pair; the report
/// and the deck.
fn direct_route(
    im: &Path,
    seg: &Path,
    out: &Path,
    solve: bool,
) -> (atlasmesh::study::MaterialsReport, std::path::PathBuf) {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/spine_benchmark");
    let vox = out.join("voxels");
    run_ok(&[
        "voxel-mesh".to_string(),
        s(seg),
        "--part".into(),
        "BONE=1,2,3,4".into(),
        "--part".into(),
        "PADS=5,6".into(),
        "--format".into(),
        "inp".into(),
        "--out".into(),
        s(&vox),
    ]);
    let mesh = find(&vox, ".inp");
    let mat = out.join("materials");
    let mut args = vec![
        "materials".to_string(),
        "--mesh".into(),
        s(&mesh),
        "--ct".into(),
        s(im),
        "--recipe".into(),
        s(&example.join("recipe.toml")),
        "--load".into(),
        s(&example.join("load.toml")),
        "--no-plots".into(),
        "--out".into(),
        s(&mat),
    ];
    if solve {
        args.push("--solve".into());
    }
    let stdout = run_ok(&args);
    assert_eq!(stdout.contains("stiffness: "), solve, "{stdout}");
    let report = serde_json::from_slice(&std::fs::read(mat.join("report.json")).unwrap()).unwrap();
    (report, find(&mat, "_materials.inp"))
}

/// The direct route reproduces the benchmark's model with its recipe as written: 10 442 N/mm
/// (the data's README: the benchmark's own code gives 12 362, every voxel a bin too stiff)
/// within 3 %; the same vertebra stored in another order gives the same model (so the same
/// stiffness).
#[test]
fn the_benchmark_vertebra_by_the_direct_route_has_the_recipes_stiffness() {
    let Some(data) = common::data_dir("spine FE benchmark, direct route") else {
        return;
    };
    let Some(py) = common::python() else { return };
    if !common::tool("ccx", "spine FE benchmark, direct route") {
        return;
    }
    let dir = common::temp_dir("spine-benchmark");
    let bench = data.join("spinefe-benchmark-L2");
    let im = bench.join("sub-verse004_0000_vertebra_21_im.nii.gz");
    let seg = bench.join("sub-verse004_0000_vertebra_21_seg.nii.gz");
    let python = |script: &str, argv: &[String]| python_json(&py, script, argv);
    let counts = python(REORIENT, &[s(&im), s(&seg), s(&dir)]);
    assert_eq!(counts["axcodes"], "SRA");
    let label = |k: usize| counts[k.to_string()].as_u64().unwrap() as usize;

    let (r, deck) = direct_route(&im, &seg, &dir.join("LPS"), true);
    let solve = r.solve.as_ref().expect("CalculiX ran");
    eprintln!(
        "direct route: {:.0} N/mm, reaction {:.1} N, CalculiX {:.1} s, {:.0} MB",
        solve.stiffness_n_per_mm, solve.reaction_n, solve.seconds, solve.peak_memory_mb
    );
    let bone: usize = (1..=4).map(label).sum();
    let pads = label(5) + label(6);
    assert_eq!(r.materials.elements, bone);
    assert_eq!(r.materials.parts[0].elements, pads);
    // Within 3 %, equilibrium along z, and nothing in the plane.
    assert_stiffness(solve, 0.03);
    let top = solve.reactions["TOP"];
    assert!(
        top[0].abs().max(top[1].abs()) < 1e-6 * top[2].abs(),
        "{top:?}"
    );

    // The deck as meshio reads it, its materials as written, the reaction as CalculiX wrote it.
    assert_eq!(deck, dir.join("LPS/materials").join(&solve.deck));
    let dat = deck.with_extension("dat");
    let back = python(READ_BACK, &[s(&deck), s(&dat)]);
    assert_eq!(back["cells"].as_u64().unwrap() as usize, bone + pads);
    assert_eq!(back["sets"]["PADS"].as_u64().unwrap() as usize, pads);
    let bone_sets: u64 = back["sets"]
        .as_object()
        .unwrap()
        .iter()
        .filter(|(k, _)| k.starts_with("BONE_"))
        .map(|(_, v)| v.as_u64().unwrap())
        .sum();
    assert_eq!(bone_sets as usize, bone);
    assert_eq!(back["materials"]["PADS"], serde_json::json!([2500.0, 0.3]));
    let materials = back["materials"].as_object().unwrap();
    assert_eq!(materials.len(), r.materials.materials);
    let sections = back["sections"].as_array().unwrap();
    assert_eq!(sections.len(), materials.len());
    for sec in sections {
        assert_eq!(
            sec[0], sec[1],
            "each section's set is its material's: {sec}"
        );
    }
    // E at the bins' centres: Kopperdahl's law, within the bone's range.
    let e_max = materials
        .iter()
        .filter(|(k, _)| k.starts_with("BONE_"))
        .map(|(_, v)| v[0].as_f64().unwrap())
        .fold(0.0, f64::max);
    let width = r.materials.bin_width.unwrap();
    assert!((width * 1000.0 - 15.03).abs() < 0.01, "bin width {width}");
    assert!(e_max <= 2980.0 * 1.894f64.powf(1.05) && e_max > 2980.0 * 1.87f64.powf(1.05));
    let rf = back["top"][2].as_f64().unwrap();
    assert!(
        (rf.abs() - solve.stiffness_n_per_mm * 0.2).abs() <= 1e-6 * rf.abs(),
        "CalculiX's reaction {rf} N against the stiffness {} N/mm × 0.2 mm",
        solve.stiffness_n_per_mm
    );

    // The same vertebra, stored S, R, A by nibabel: the same model, node for node, element for
    // element, modulus for modulus, with the same load case (so the same stiffness, without a
    // second solve of 80 s).
    let (r2, deck2) = direct_route(
        &dir.join("im_SRA.nii.gz"),
        &dir.join("seg_SRA.nii.gz"),
        &dir.join("SRA"),
        false,
    );
    assert!(r2.solve.is_none());
    assert_eq!(r2.materials.elements, bone);
    let same = python(SAME_MODEL, &[s(&deck), s(&deck2)]);
    eprintln!("direct route, stored S,R,A: {same}");
    assert_eq!(same["elements"][0].as_u64().unwrap() as usize, bone + pads);
    assert_eq!(same["unmapped"], 0, "every element has a material: {same}");
    assert_eq!(same["load_sets"], serde_json::json!(["BOTTOM", "TOP"]));
    for key in ["same_nodes", "same_elements", "same_load_sets", "same_step"] {
        assert_eq!(same[key], true, "{key}: {same}");
    }
}

/// `fit` of the bone's labels (1-4) of the label map `seg` with `atlas`, `.inp` into `out`,
/// with `extra` options.
fn fit_bone(atlas: &Path, seg: &Path, out: &Path, extra: &[&str]) {
    let mut args: Vec<String> = vec![
        "fit".into(),
        "--atlas".into(),
        s(atlas),
        "--subjects".into(),
        s(seg),
        "--label".into(),
        "1,2,3,4".into(),
        "--format".into(),
        "inp".into(),
        "--out".into(),
        s(out),
    ];
    args.extend(extra.iter().map(|a| a.to_string()));
    run_ok(&args);
}

/// `voxel-mesh` of the pads (labels 5, 6) of `seg` tied to the fitted bone `fitted`, `.inp`
/// into `out`; what it said.
fn join_pads(seg: &Path, fitted: &Path, out: &Path) -> String {
    run_ok(&[
        "voxel-mesh".into(),
        s(seg),
        "--part".into(),
        "PADS=5,6".into(),
        "--join".into(),
        s(fitted),
        "--format".into(),
        "inp".into(),
        "--out".into(),
        s(out),
    ])
}

/// `materials` of the joined mesh in `joined` on the CT `ct` with the atlas route's recipe
/// and load case, solved by CalculiX, into `out` (with `extra` options); its report.
fn atlas_materials(
    joined: &Path,
    ct: &Path,
    out: &Path,
    extra: &[&str],
) -> atlasmesh::study::MaterialsReport {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/spine_benchmark");
    let mut args: Vec<String> = vec![
        "materials".into(),
        "--mesh".into(),
        s(&find(joined, "_joined.inp")),
        "--ct".into(),
        s(ct),
        "--recipe".into(),
        s(&example.join("atlas_recipe.toml")),
        "--load".into(),
        s(&example.join("atlas_load.toml")),
        "--solve".into(),
        "--out".into(),
        s(out),
    ];
    args.extend(extra.iter().map(|a| a.to_string()));
    run_ok(&args);
    serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap()
}

/// The path in `dir` whose name ends with `suffix`.
fn find(dir: &Path, suffix: &str) -> std::path::PathBuf {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.to_string_lossy().ends_with(suffix))
        .unwrap_or_else(|| panic!("no *{suffix} in {}", dir.display()))
}

/// Runs the command-line tool; panics with what it printed when it fails.
fn run_ok(args: &[String]) -> String {
    let o = common::atlasmesh(args);
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        o.status.success(),
        "atlasmesh {args:?}: {}{stdout}",
        String::from_utf8_lossy(&o.stderr)
    );
    stdout
}

/// The atlas route, with default options: an atlas of the 10 VerSe L1 vertebrae (`build
/// --register`), fitted to the bone's labels 1-4 (`fit`), the pads joined to the fitted mesh by
/// a tie (`voxel-mesh --join`), the benchmark's recipe with Bonemat's V3 integration and the
/// same compression test with the tie (`materials --load --solve`). The stiffness within 10 %
/// of the recipe's 10 442 N/mm (a smooth boundary instead of voxel steps, its own element
/// size: not the same model, the same bone); the deck as meshio reads it: the bone's elements
/// those of the fitted mesh, the pads' those of the label map, the tie's nodes a set; the
/// `.feb` model with the same step; the page in Chromium; the same vertebra stored S, R, A as
/// stiff within 1 %.
#[test]
fn the_benchmark_vertebra_by_the_atlas_route_is_as_stiff_within_ten_percent() {
    let Some(data) = common::data_dir("spine FE benchmark, atlas route") else {
        return;
    };
    let Some(py) = common::python() else { return };
    if !common::tool("ccx", "spine FE benchmark, atlas route") {
        return;
    }
    let dir = common::temp_dir("spine-atlas-route");
    let bench = data.join("spinefe-benchmark-L2");
    let im = bench.join("sub-verse004_0000_vertebra_21_im.nii.gz");
    let seg = bench.join("sub-verse004_0000_vertebra_21_seg.nii.gz");
    let atlas = dir.join("l1.safetensors");
    run_ok(&[
        "build".into(),
        "--register".into(),
        "--shapes".into(),
        s(&data.join("verse-L1-vertebrae-3d/raw")),
        "--out".into(),
        s(&atlas),
    ]);
    let fit = dir.join("fit");
    fit_bone(&atlas, &seg, &fit, &[]);
    let report: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(fit.join("report.json")).unwrap()).unwrap();
    let subject = &report.subjects[0];
    assert!(subject.success, "{:?}", subject.failed_checks);
    assert_eq!(subject.inverted_elements, 0);
    assert!(
        subject.mesh_rms_distance < 0.5 * subject.element_size,
        "the delivered mesh {} mm from the bone's labels",
        subject.mesh_rms_distance
    );
    // The subject's page names the bound its verdict used beside the stricter usual one, and
    // flags a large edge ratio.
    let page = std::fs::read_to_string(find(&fit.join(&subject.name), ".html")).unwrap();
    assert!(
        page.contains("at or above the repair bound 0.20"),
        "the verdict"
    );
    assert_eq!(
        page.contains("The largest edge ratio"),
        subject.edge_ratio_max > 10.0,
        "edge ratio {}",
        subject.edge_ratio_max
    );
    if subject.elements_below_bound > 0 {
        assert!(page.contains("which the checks above do not require"));
    }
    let fitted = find(&fit.join(&subject.name), "_mesh.inp");
    let bone_elements = atlasmesh::formats::read_fe_mesh::<3>(&fitted)
        .unwrap()
        .num_elements();
    let joined = dir.join("joined");
    let said = join_pads(&seg, &fitted, &joined);
    assert!(said.contains("BONE_TIED"), "{said}");
    let mat = dir.join("materials");
    let r = atlas_materials(&joined, &im, &mat, &["--format", "inp,vtu,feb"]);
    let solve = r.solve.as_ref().expect("CalculiX ran");
    eprintln!(
        "atlas route: {:.0} N/mm, {bone_elements} bone elements (min scaled Jacobian {:.2}), \
         CalculiX {:.1} s, {:.0} MB",
        solve.stiffness_n_per_mm, subject.scaled_jacobian_min, solve.seconds, solve.peak_memory_mb
    );
    assert_stiffness(solve, 0.10);
    // The displacements CalculiX wrote: the top face's 0.2 mm at least, nothing flying off;
    // their picture written.
    let largest = solve.largest_displacement_mm.unwrap();
    assert!((0.2..1.0).contains(&largest), "{largest} mm");
    let picture = r
        .files
        .iter()
        .find(|f| f.ends_with("_displacement.png"))
        .expect("the displacement's picture");
    assert!(std::fs::metadata(mat.join(picture)).unwrap().len() > 10_000);
    // The page: the stiffness, the pictures (the displacement, the histogram of E) loaded in
    // Chromium, every file linked.
    let page = std::fs::read_to_string(mat.join("report.html")).unwrap();
    assert!(
        page.contains(&format!(
            "Stiffness <b>{:.0} N/mm</b>",
            solve.stiffness_n_per_mm
        )),
        "the stiffness on the page"
    );
    if common::tool("chromium", "the materials page in a browser") {
        crate::html::open(&mat.join("report.html"), 2, r.files.len() + 1);
    }

    // The deck as meshio reads it: bone and pads, the tie's node set, the tie in the step.
    let deck = mat.join(&solve.deck);
    let back = python_json(&py, READ_BACK, &[s(&deck), s(&deck.with_extension("dat"))]);
    let pads = r.materials.parts[0].elements;
    assert_eq!(
        back["cells"].as_u64().unwrap() as usize,
        bone_elements + pads
    );
    assert_eq!(
        back["sets"]["BONE"].as_u64().unwrap() as usize,
        bone_elements
    );
    assert_eq!(back["sets"]["PADS"].as_u64().unwrap() as usize, pads);
    assert_eq!(back["materials"]["PADS"], serde_json::json!([2500.0, 0.3]));
    let tied = back["point_sets"]["BONE_TIED"].as_u64().unwrap() as usize;
    assert!(tied > 1000, "{tied} tied nodes");
    // CalculiX ties (almost) every one of them.
    assert!(
        solve.untied_nodes * 100 < tied,
        "{} of {tied} untied",
        solve.untied_nodes
    );
    let text = std::fs::read_to_string(&deck).unwrap();
    assert!(text.contains("*TIE, NAME=TIE_1") && text.contains("TIE_1_NODES, BONE_SURFACE"));
    // The same model and step for FEBio: every element in a domain with its material, the
    // tie's side made of tied nodes only, paired with the bone's surface.
    let feb = python_json(&py, FEB_READ_BACK, &[s(&deck.with_extension("feb"))]);
    assert_eq!(
        feb["elements"].as_u64().unwrap() as usize,
        bone_elements + pads
    );
    assert_eq!(feb["domains"], feb["materials"]);
    assert_eq!(feb["side_nodes_tied"], true);
    assert!(feb["side_faces"].as_u64().unwrap() > 500, "{feb}");
    assert_eq!(feb["contact"], "tied-node-on-facet");
    assert_eq!(feb["prescribed"], serde_json::json!([["TOP", "z", -0.2]]));

    // The same vertebra stored S, R, A (nibabel): the same fitted bone (95 % of its nodes
    // within a quarter of an element) and the same stiffness within 1 %.
    let counts = python_json(&py, REORIENT, &[s(&im), s(&seg), s(&dir)]);
    assert_eq!(counts["axcodes"], "SRA");
    let fit2 = dir.join("fit-SRA");
    let seg2 = dir.join("seg_SRA.nii.gz");
    fit_bone(&atlas, &seg2, &fit2, &["--no-plots"]);
    let fitted2 = find(&fit2.join("seg_SRA"), "_mesh.inp");
    let a = atlasmesh::formats::read_fe_mesh::<3>(&fitted).unwrap();
    let b = atlasmesh::formats::read_fe_mesh::<3>(&fitted2).unwrap();
    assert_eq!(a.nodes.len(), b.nodes.len());
    let mut apart: Vec<f64> = a
        .nodes
        .iter()
        .zip(&b.nodes)
        .map(|(p, q)| atlasmesh::geometry::dist2(*p, *q).sqrt() / subject.element_size)
        .collect();
    apart.sort_by(f64::total_cmp);
    let at = |q: f64| apart[(q * (apart.len() - 1) as f64).round() as usize];
    let joined2 = dir.join("joined-SRA");
    join_pads(&seg2, &fitted2, &joined2);
    let mat2 = dir.join("materials-SRA");
    let r2 = atlas_materials(
        &joined2,
        &dir.join("im_SRA.nii.gz"),
        &mat2,
        &["--format", "inp", "--no-plots"],
    );
    let k2 = r2.solve.as_ref().expect("CalculiX ran").stiffness_n_per_mm;
    eprintln!(
        "atlas route stored S,R,A: {k2:.0} N/mm; nodes apart by a median {:.4}, 95th percentile \
         {:.4}, largest {:.3} elements; mean E {:.1} against {:.1} MPa",
        at(0.5),
        at(0.95),
        at(1.0),
        r2.materials.modulus_mean,
        r.materials.modulus_mean
    );
    assert!(
        at(0.95) <= 0.25,
        "95 % of the nodes within {} elements",
        at(0.95)
    );
    assert_eq!(r2.materials.parts[0].elements, pads);
    assert!(
        (k2 / solve.stiffness_n_per_mm - 1.0).abs() <= 0.01,
        "{k2:.0} against {:.0} N/mm",
        solve.stiffness_n_per_mm
    );
}

/// A `.feb` model with a tied step as an XML parser reads it.
const FEB_READ_BACK: &str = r#"
import sys, json, xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
sets = {s.get("name"): set(int(i) for i in s.text.split(",")) for s in root.iter("NodeSet")}
side = root.find("Mesh/Surface[@name='TIE_1_NODES']")
nodes = set(int(i) for f in side for i in f.text.split(","))
print(json.dumps({
  "elements": sum(len(e) for e in root.iter("Elements")),
  "materials": len(root.findall("Material/material")),
  "domains": len(root.findall("MeshDomains/SolidDomain")),
  "side_faces": len(side),
  "side_nodes_tied": nodes <= sets["BONE_TIED"],
  "contact": root.find("Contact/contact").get("type"),
  "prescribed": [[b.get("node_set"), b.findtext("dof"), float(b.findtext("value"))]
                 for b in root.iter("bc") if b.get("type") == "prescribed displacement"],
}))
"#;
