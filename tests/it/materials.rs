//! Materials from a CT, checked on what is delivered: TotalSegmentator's L1 fitted with its
//! CT, every solver file read back by another program (meshio, febio-python, Gmsh) and the
//! graded vertebra solved by CalculiX; the CT's HU resampled independently at the elements;
//! the same CT written as NRRD (LPS) and a DICOM series read through SimpleITK; a metal
//! implant written into the CT with nibabel; ramps written by nibabel under tetrahedra that
//! Gmsh meshed; CTs paired with subjects by folder and table; bad inputs.

use crate::common;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn run_ok(args: &[String]) -> std::process::Output {
    let o = common::atlasmesh(args);
    assert!(
        o.status.success(),
        "atlasmesh {args:?}: {}{}",
        String::from_utf8_lossy(&o.stderr),
        String::from_utf8_lossy(&o.stdout)
    );
    o
}

fn args(v: &[&str]) -> Vec<String> {
    v.iter().map(|a| a.to_string()).collect()
}

/// Runs a Python script with `argv`; its stdout. Fails with its output.
fn python(py: &Path, script: &str, argv: &[String]) -> String {
    let o = crate::common::run(
        std::process::Command::new(py)
            .arg("-c")
            .arg(script)
            .args(argv),
        crate::common::deadline::PYTHON,
    );
    assert!(
        o.status.success(),
        "python: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// An atlas of the 10 VerSe L1 vertebrae with a coarse (2 mm) mean mesh.
fn vertebra_atlas(data: &Path, dir: &Path) -> PathBuf {
    let raw = data.join("verse-L1-vertebrae-3d/raw");
    let mut shapes: Vec<String> = std::fs::read_dir(&raw)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .map(|p| s(&p))
        .collect();
    shapes.sort();
    let atlas = dir.join("atlas.safetensors");
    let mut a = args(&[
        "build",
        "--register",
        "--element-size",
        "2",
        "--no-plots",
        "--shapes",
    ]);
    a.extend(shapes);
    a.extend(["--out".into(), s(&atlas)]);
    run_ok(&a);
    atlas
}

/// The per-element HU of a mesh file resampled independently: the CT read by nibabel,
/// trilinear (numpy) at each cell's centroid (mean of its corners); prints the median
/// absolute difference to the file's `HU`, their correlation, and the volume-blind mean of
/// both.
const RESAMPLE: &str = r#"
import sys, json, numpy as np, meshio, nibabel as nib
mesh = meshio.read(sys.argv[1]); img = nib.load(sys.argv[2])
ct = np.asarray(img.dataobj, dtype=np.float64) * 1.0
slope, inter = img.dataobj.slope, img.dataobj.inter
ct = ct if (slope is None or np.isnan(slope)) else ct * slope + (0 if inter is None or np.isnan(inter) else inter)
cells = mesh.cells[0].data[:, :8]
c = mesh.points[cells].mean(axis=1)
ijk = (np.linalg.inv(img.affine) @ np.c_[c, np.ones(len(c))].T)[:3].T
ijk = np.clip(ijk, 0, np.array(ct.shape) - 1.000001)
i0 = np.floor(ijk).astype(int); f = ijk - i0
v = 0
for dx in (0, 1):
    for dy in (0, 1):
        for dz in (0, 1):
            w = (f[:, 0] if dx else 1 - f[:, 0]) * (f[:, 1] if dy else 1 - f[:, 1]) * (f[:, 2] if dz else 1 - f[:, 2])
            v = v + w * ct[i0[:, 0] + dx, i0[:, 1] + dy, i0[:, 2] + dz]
hu = mesh.cell_data["HU"][0]
print(json.dumps({"median_abs": float(np.median(np.abs(hu - v))), "corr": float(np.corrcoef(hu, v)[0, 1]),
                  "mean_file": float(hu.mean()), "mean_resampled": float(v.mean()), "cells": int(len(hu))}))
"#;

/// Every format's per-element values as other programs read them back: meshio's cell data
/// of .vtu, .vtk and .msh equal, febio-python's materials one per group of E.
const READ_BACK: &str = r#"
import sys, json, numpy as np, meshio
from febio_python.feb import Feb
base = sys.argv[1]
v = meshio.read(base + ".vtu")
E = v.cell_data["E"][0]
for ext in ["vtk", "msh"]:
    m = meshio.read(base + "." + ext)
    e = np.ravel(m.cell_data["E"][0])
    assert e.shape == E.shape and np.abs(e - E).max() <= 1e-9 * E.max(), ext
feb = Feb(filepath=base + ".feb")
mats = feb.get_materials()
E_feb = sorted(float(m.parameters["E"]) for m in mats)
doms = feb.get_mesh_domains()
assert len(doms) == len(mats), (len(doms), len(mats))
n = sum(len(np.asarray(p.connectivity)) for p in feb.get_elements())
assert n == len(E), (n, len(E))
print(json.dumps({"materials": len(mats), "E_min_feb": E_feb[0], "E_max_feb": E_feb[-1], "E_min": float(E.min()), "E_max": float(E.max())}))
"#;

/// The reaction of a CalculiX step that compresses `deck`'s mesh by 0.1 mm between its
/// lowest and highest 5 % of nodes (z): the stiffness in N/mm.
fn calculix_stiffness(mesh_inp: &Path, dir: &Path, name: &str) -> f64 {
    let mesh: atlasmesh::mesh::FeMesh<3> = atlasmesh::formats::read_fe_mesh(mesh_inp).unwrap();
    let (lo, hi) = mesh
        .nodes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[2]), b.max(p[2]))
        });
    let band = 0.05 * (hi - lo);
    let ids = |f: &dyn Fn(f64) -> bool| -> String {
        let v: Vec<String> = (0..mesh.nodes.len())
            .filter(|&n| f(mesh.nodes[n][2]))
            .map(|n| (n + 1).to_string())
            .collect();
        v.chunks(16)
            .map(|c| c.join(", "))
            .collect::<Vec<_>>()
            .join("\n")
    };
    let deck = dir.join(format!("{name}.inp"));
    let text = std::fs::read_to_string(mesh_inp).unwrap()
        + &format!(
            "*NSET, NSET=BOTTOM\n{}\n*NSET, NSET=TOP\n{}\n*STEP\n*STATIC\n*BOUNDARY\nBOTTOM, 1, 3, 0.\nTOP, 1, 2, 0.\nTOP, 3, 3, -0.1\n*NODE PRINT, NSET=TOP, TOTALS=ONLY\nRF\n*END STEP\n",
            ids(&|z| z <= lo + band),
            ids(&|z| z >= hi - band)
        );
    std::fs::write(&deck, text).unwrap();
    let o = crate::common::run(
        std::process::Command::new("ccx")
            .arg("-i")
            .arg(name)
            .current_dir(dir),
        crate::common::deadline::CCX,
    );
    let log = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && !log.contains("*ERROR"), "ccx: {log}");
    let dat = std::fs::read_to_string(dir.join(format!("{name}.dat"))).unwrap();
    let after = dat
        .split("total force")
        .nth(1)
        .expect("total force in the .dat");
    let fz: f64 = after
        .lines()
        .skip(1)
        .find_map(|l| {
            let f: Vec<f64> = l
                .split_whitespace()
                .filter_map(|v| v.parse().ok())
                .collect();
            (f.len() == 3).then(|| f[2])
        })
        .unwrap();
    fz.abs() / 0.1
}

#[test]
fn totalsegmentators_l1_gets_its_materials_from_its_ct_in_every_solver_file() {
    let Some(data) = common::data_dir("materials from TotalSegmentator's CT") else {
        return;
    };
    let dir = common::temp_dir("materials-l1");
    let atlas = vertebra_atlas(&data, &dir);
    let ts = data.join("totalseg-example-ct-3d");
    let ct = ts.join("example_ct_sm.nii.gz");
    let out = dir.join("fit");
    run_ok(&args(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subjects",
        &s(&ts.join("example_seg.nii.gz")),
        "--label",
        "vertebrae_L1",
        "--label-table",
        &s(&ts.join("labels_total.csv")),
        "--ct",
        &s(&ct),
        "--format",
        "inp,vtu,vtk,msh,feb",
        "--out",
        &s(&out),
    ]));
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let subject = &r.subjects[0];
    assert!(subject.success, "{:?}", subject.failed_checks);
    let m = subject
        .materials
        .as_ref()
        .expect("materials in report.json");
    let base = out.join("example_seg/example_seg_mesh");
    let mesh: atlasmesh::mesh::FeMesh<3> =
        atlasmesh::formats::read_fe_mesh(&base.with_extension("vtu")).unwrap();
    assert_eq!(m.elements, mesh.num_elements());
    assert_eq!(m.partly_outside, 0);
    assert!(m.modulus_min >= m.recipe.modulus.floor && m.modulus_max > m.modulus_min);
    // The mean HU of the mesh beside the label's (196.2, nibabel): the mesh's boundary lies on
    // the label's surface, so partial volume at 3 mm lowers it a little.
    eprintln!(
        "L1 on its CT: mean HU {:.1} (label 196.2), E {:.0}..{:.0} MPa, {} materials, gap {:.2} MPa, partial volume {:.2}",
        m.mean_hu, m.modulus_min, m.modulus_max, m.materials, m.gap, m.partial_volume_share
    );
    assert!((m.mean_hu - 196.2).abs() < 40.0, "{}", m.mean_hu);
    // The page shows the materials and the histogram of E; the viewer colours by E.
    let page = std::fs::read_to_string(out.join("example_seg/example_seg.html")).unwrap();
    assert!(page.contains("Materials from the CT") && page.contains("example_seg_E.png"));
    assert!(page.contains("Young's modulus from the CT"));
    assert!(out.join("example_seg/example_seg_E.png").is_file());
    let Some(py) = common::python() else { return };
    // The HU written per element, against the CT resampled by nibabel and numpy.
    let v: serde_json::Value = serde_json::from_str(&python(
        &py,
        RESAMPLE,
        &[s(&base.with_extension("vtu")), s(&ct)],
    ))
    .unwrap();
    eprintln!("resampled: {v}");
    assert!(v["median_abs"].as_f64().unwrap() < 15.0, "{v}");
    assert!(v["corr"].as_f64().unwrap() > 0.95, "{v}");
    // Every format read back.
    let v: serde_json::Value = serde_json::from_str(&python(&py, READ_BACK, &[s(&base)])).unwrap();
    eprintln!("read back: {v}");
    assert_eq!(v["materials"].as_u64().unwrap() as usize, m.materials);
    assert!(
        (v["E_min_feb"].as_f64().unwrap() - v["E_min"].as_f64().unwrap()).abs() <= m.gap + 1e-6
    );
    if common::tool("gmsh", "gmsh -check of a .msh with element data") {
        let o = crate::common::run(
            std::process::Command::new("gmsh")
                .arg("-check")
                .arg(base.with_extension("msh")),
            crate::common::deadline::GMSH,
        );
        let log =
            String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success() && !log.contains("Error"), "{log}");
    }
    // CalculiX solves the graded vertebra in compression; and the same mesh of one material
    // at the graded mesh's volume-weighted mean E, for comparison.
    if common::tool("ccx", "CalculiX solves the graded vertebra") {
        let k = calculix_stiffness(&base.with_extension("inp"), &dir, "graded");
        let uniform = dir.join("uniform_mesh.inp");
        let text = std::fs::read_to_string(base.with_extension("inp")).unwrap();
        let cut = text.find("** Materials from the CT").unwrap();
        std::fs::write(
            &uniform,
            format!(
                "{}*MATERIAL, NAME=MEAN\n*ELASTIC\n{:.6e}, 0.3\n*SOLID SECTION, ELSET=EALL, MATERIAL=MEAN\n",
                &text[..cut],
                m.modulus_mean
            ),
        )
        .unwrap();
        let k_uniform = calculix_stiffness(&uniform, &dir, "uniform");
        eprintln!(
            "CalculiX: graded L1 compressed between its lowest and highest 5 %: stiffness {k:.0} N/mm (one material of the mean E: {k_uniform:.0} N/mm)"
        );
        assert!(k.is_finite() && k > 1e2 && k < 1e6, "{k}");
        assert!(
            (k - k_uniform).abs() > 1e-3 * k_uniform,
            "the grading changes the answer"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Writes, with nibabel, a copy of the CT with a 4-voxel cube of 8000 HU at the centroid of
/// `label`, and the CT as NRRD (LPS) with SimpleITK.
const WRITE_CTS: &str = r#"
import sys, numpy as np, nibabel as nib, SimpleITK as sitk
ct, seg, label, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
img = nib.load(ct); a = np.asarray(img.dataobj).copy()
lab = np.argwhere(np.asarray(nib.load(seg).dataobj) == label).mean(axis=0).round().astype(int)
a[lab[0]-1:lab[0]+2, lab[1]-1:lab[1]+2, lab[2]-1:lab[2]+2] = 8000
nib.save(nib.Nifti1Image(a, img.affine, img.header), out + "/metal.nii.gz")
sitk.WriteImage(sitk.ReadImage(ct), out + "/ct.nrrd")
"#;

#[test]
fn any_mesh_mapped_by_the_materials_command_metal_flagged_lps_the_same() {
    let Some(data) = common::data_dir("materials of a mesh made elsewhere") else {
        return;
    };
    let Some(py) = common::python() else { return };
    let dir = common::temp_dir("materials-command");
    let atlas = vertebra_atlas(&data, &dir);
    let ts = data.join("totalseg-example-ct-3d");
    let ct = ts.join("example_ct_sm.nii.gz");
    let fit = dir.join("fit");
    run_ok(&args(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subjects",
        &s(&ts.join("example_seg.nii.gz")),
        "--label",
        "31",
        "--no-plots",
        "--out",
        &s(&fit),
    ]));
    let mesh = fit.join("example_seg/example_seg_mesh.vtu");
    python(
        &py,
        WRITE_CTS,
        &[
            s(&ct),
            s(&ts.join("example_seg.nii.gz")),
            "31".into(),
            s(&dir),
        ],
    );
    let map = |ct: &Path, out: &str| -> (atlasmesh::study::MaterialsReport, String) {
        let o = run_ok(&args(&[
            "materials",
            "--mesh",
            &s(&mesh),
            "--ct",
            &s(ct),
            "--format",
            "vtu,inp",
            "--out",
            &s(&dir.join(out)),
        ]));
        let r = serde_json::from_slice(&std::fs::read(dir.join(out).join("report.json")).unwrap())
            .unwrap();
        (r, String::from_utf8_lossy(&o.stdout).to_string())
    };
    let (nifti, _) = map(&ct, "nifti");
    assert_eq!(nifti.materials.metal_elements, 0);
    assert!(dir.join("nifti/example_seg_mesh_E.png").is_file());
    // Its page: the map's figures and the histogram, loaded in Chromium with every link a file.
    let page = std::fs::read_to_string(dir.join("nifti/report.html")).unwrap();
    assert!(page.contains("Materials from the CT") && page.contains("example_seg_mesh_E.png"));
    assert!(page.contains(&format!(
        "<td>elements</td><td>{}</td>",
        nifti.materials.elements
    )));
    if common::tool("chromium", "the materials page in a browser") {
        crate::html::open(&dir.join("nifti/report.html"), 1, nifti.files.len() + 1);
    }
    // The same CT as NRRD in LPS: the same values.
    let (nrrd, _) = map(&dir.join("ct.nrrd"), "nrrd");
    let e = |d: &str| -> Vec<f64> {
        let m = atlasmesh::formats::read_vtu(&dir.join(d).join("example_seg_mesh_materials.vtu"));
        assert!(m.is_ok());
        let py_out = python(
            &py,
            "import sys, json, meshio; print(json.dumps(meshio.read(sys.argv[1]).cell_data['E'][0].tolist()))",
            &[s(&dir.join(d).join("example_seg_mesh_materials.vtu"))],
        );
        serde_json::from_str(&py_out).unwrap()
    };
    let (a, b) = (e("nifti"), e("nrrd"));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert!(
            (x - y).abs() <= 1e-6 * x.abs(),
            "NIfTI {x} vs NRRD (LPS) {y}"
        );
    }
    assert!((nifti.materials.mean_hu - nrrd.materials.mean_hu).abs() < 1e-6);
    // A metal implant inside the bone: flagged in the report and the summary line.
    let (metal, line) = map(&dir.join("metal.nii.gz"), "metal");
    assert!(metal.materials.metal_elements > 0);
    assert!(
        metal
            .materials
            .warnings
            .iter()
            .any(|w| w.starts_with("metal"))
    );
    assert!(line.contains("metal"), "{line}");
    // A fit with the metal CT: its report and summary line say so too.
    let o = common::atlasmesh(&args(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subjects",
        &s(&ts.join("example_seg.nii.gz")),
        "--label",
        "31",
        "--ct",
        &s(&dir.join("metal.nii.gz")),
        "--no-plots",
        "--out",
        &s(&dir.join("fit-metal")),
    ]));
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{text}");
    assert!(text.contains("metal"), "{text}");
    // Moved 500 mm away: an error that says how much lies outside, nothing written.
    let far = dir.join("far.vtu");
    let mut moved: atlasmesh::mesh::FeMesh<3> = atlasmesh::formats::read_fe_mesh(&mesh).unwrap();
    for p in &mut moved.nodes {
        p[0] += 500.0;
    }
    atlasmesh::formats::write_vtu(&far, &moved, None).unwrap();
    let o = common::atlasmesh(&args(&[
        "materials",
        "--mesh",
        &s(&far),
        "--ct",
        &s(&ct),
        "--out",
        &s(&dir.join("far")),
    ]));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("outside the CT") && err.contains("100.0 %"),
        "{err}"
    );
    assert!(!dir.join("far/report.json").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// A CT linear in position written by nibabel (oblique, anisotropic voxels, float64), and
/// a box meshed by Gmsh into quadratic tetrahedra.
const RAMP_AND_TETS: &str = r#"
import sys, numpy as np, nibabel as nib
out = sys.argv[1]
# (Values exact in float32: the NIfTI header stores the affine in float32.)
aff = np.array([[0.75, 0.125, 0, -30], [-0.0625, 0.625, 0, -25], [0, 0, 1.5, -20], [0, 0, 0, 1]])
i, j, k = np.meshgrid(np.arange(80), np.arange(80), np.arange(40), indexing="ij")
xyz = np.einsum("rc,cijk->rijk", aff[:3, :3], np.stack([i, j, k])) + aff[:3, 3, None, None, None]
hu = 200 + 9 * xyz[0] - 4 * xyz[1] + 6 * xyz[2]
nib.save(nib.Nifti1Image(hu.astype(np.float64), aff), out + "/ramp.nii.gz")
open(out + "/box.geo", "w").write('SetFactory("OpenCASCADE");\nBox(1) = {-10, -8, -5, 18, 14, 12};\nMesh.CharacteristicLengthMax = 4;\n')
"#;

#[test]
fn quadratic_tetrahedra_from_gmsh_on_a_ramp_written_by_nibabel_are_exact() {
    let Some(py) = common::python() else { return };
    if !common::tool("gmsh", "Gmsh meshes a box into tet10") {
        return;
    }
    let dir = common::temp_dir("materials-ramp");
    python(&py, RAMP_AND_TETS, &[s(&dir)]);
    let o = crate::common::run(
        std::process::Command::new("gmsh")
            .args(["-3", "-order", "2", "-format", "msh41"])
            .arg(dir.join("box.geo"))
            .arg("-o")
            .arg(dir.join("box.msh")),
        crate::common::deadline::GMSH,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let recipe = dir.join("recipe.toml");
    std::fs::write(&recipe, "[calibration]\nslope = 0.001\nintercept = 0.05\n").unwrap();
    run_ok(&args(&[
        "materials",
        "--mesh",
        &s(&dir.join("box.msh")),
        "--ct",
        &s(&dir.join("ramp.nii.gz")),
        "--recipe",
        &s(&recipe),
        "--format",
        "vtu",
        "--out",
        &s(&dir.join("out")),
    ]));
    let vtu = dir.join("out/box_materials.vtu");
    let mesh: atlasmesh::mesh::FeMesh<3> = atlasmesh::formats::read_fe_mesh(&vtu).unwrap();
    assert_eq!(mesh.kind, atlasmesh::mesh::ElementKind::Tet10);
    let check = r#"
import sys, json, numpy as np, meshio
m = meshio.read(sys.argv[1])
cells = m.cells[0].data
c = m.points[cells[:, :4]].mean(axis=1)  # straight-sided tetrahedra: the centroid of the corners
want = 200 + 9 * c[:, 0] - 4 * c[:, 1] + 6 * c[:, 2]
got = m.cell_data["HU"][0]
print(json.dumps({"rel": float(np.max(np.abs(got - want)) / np.max(np.abs(want))), "n": int(len(got))}))
"#;
    let v: serde_json::Value = serde_json::from_str(&python(&py, check, &[s(&vtu)])).unwrap();
    eprintln!("tet10 on a ramp: {v}");
    assert!(v["n"].as_u64().unwrap() > 50);
    assert!(v["rel"].as_f64().unwrap() < 1e-9, "{v}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn cts_paired_with_subjects_by_folder_and_table_and_bad_pairings_refused() {
    let Some(data) = common::data_dir("CTs paired with subjects") else {
        return;
    };
    let dir = common::temp_dir("materials-pairing");
    let atlas = vertebra_atlas(&data, &dir);
    let ts = data.join("totalseg-example-ct-3d");
    // Two subjects (the same label map under two names), their CTs in a folder by name.
    let subjects = dir.join("subjects");
    let cts = dir.join("cts");
    std::fs::create_dir_all(&subjects).unwrap();
    std::fs::create_dir_all(&cts).unwrap();
    for n in ["a", "b"] {
        std::os::unix::fs::symlink(
            ts.join("example_seg.nii.gz"),
            subjects.join(format!("{n}.nii.gz")),
        )
        .unwrap();
        std::os::unix::fs::symlink(
            ts.join("example_ct_sm.nii.gz"),
            cts.join(format!("{n}.nii.gz")),
        )
        .unwrap();
    }
    let fit = |ct: &Path, out: &str| {
        common::atlasmesh(&args(&[
            "fit",
            "--atlas",
            &s(&atlas),
            "--subjects",
            &s(&subjects),
            "--label",
            "31",
            "--ct",
            &s(ct),
            "--no-plots",
            "--out",
            &s(&dir.join(out)),
        ]))
    };
    let means = |out: &str| -> Vec<f64> {
        let r: atlasmesh::report::Report =
            serde_json::from_slice(&std::fs::read(dir.join(out).join("report.json")).unwrap())
                .unwrap();
        r.subjects
            .iter()
            .map(|s| s.materials.as_ref().unwrap().mean_hu)
            .collect()
    };
    let o = fit(&cts, "by-folder");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let folder = means("by-folder");
    assert_eq!(folder.len(), 2);
    let table = dir.join("cts.csv");
    std::fs::write(&table, "subject,ct\na,cts/a.nii.gz\nb,cts/b.nii.gz\n").unwrap();
    let o = fit(&table, "by-table");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(means("by-table"), folder);
    // One CT for two subjects; a table without one of them; a folder without one.
    let o = fit(&ts.join("example_ct_sm.nii.gz"), "one");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("one CT for 2 subject files"));
    std::fs::write(&table, "subject,ct\na,cts/a.nii.gz\n").unwrap();
    let o = fit(&table, "short-table");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("no row for subject b"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::remove_file(cts.join("b.nii.gz")).unwrap();
    let o = fit(&cts, "short-folder");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("no CT for subject b"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // A recipe with a typo names the file and the field.
    let recipe = dir.join("r.toml");
    std::fs::write(&recipe, "[modulus]\nlaw = \"morgan-2003-vertebrae\"\n").unwrap();
    let o = common::atlasmesh(&args(&[
        "materials",
        "--mesh",
        "x.vtu",
        "--ct",
        &s(&ts.join("example_ct_sm.nii.gz")),
        "--recipe",
        &s(&recipe),
        "--out",
        &s(&dir.join("r")),
    ]));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("r.toml") && err.contains("morgan-2003-vertebra,"),
        "{err}"
    );
    assert!(!dir.join("r").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// A Python function the block scripts start with: `hex_block(n)`, the integer corners
/// (x slowest) and the hexahedra (VTK order, x, y, z) of an n × n × n block of unit cubes.
const HEX_BLOCK: &str = r#"
import numpy as np
def hex_block(n):
    g = np.stack(np.meshgrid(*[np.arange(n + 1)] * 3, indexing="ij"), -1).reshape(-1, 3)
    idx = lambda x, y, z: (x * (n + 1) + y) * (n + 1) + z
    cells = [[idx(x, y, z), idx(x + 1, y, z), idx(x + 1, y + 1, z), idx(x, y + 1, z),
              idx(x, y, z + 1), idx(x + 1, y, z + 1), idx(x + 1, y + 1, z + 1), idx(x, y + 1, z + 1)]
             for x in range(n) for y in range(n) for z in range(n)]
    return g, np.array(cells)
"#;

/// With SimpleITK: the DICOM series read and written as NIfTI, and a block of hexahedra
/// (meshio) around the centre of the series' extent, in RAS.
const DICOM_AND_BLOCK: &str = r#"
import sys, numpy as np, SimpleITK as sitk, meshio
series, out = sys.argv[1], sys.argv[2]
r = sitk.ImageSeriesReader(); r.SetFileNames(r.GetGDCMSeriesFileNames(series))
img = r.Execute()
sitk.WriteImage(img, out + "/dicom.nii.gz")
size = np.array(img.GetSize())
c_lps = np.array(img.TransformContinuousIndexToPhysicalPoint(((size - 1) / 2.0).tolist()))
c = c_lps * np.array([-1, -1, 1])
n = 6
g, cells = hex_block(n)
nodes = c + 3.0 * (g - n / 2)
meshio.Mesh(nodes, [("hexahedron", cells)]).write(out + "/block.vtu")
"#;

#[test]
fn a_dicom_series_gives_the_materials_of_its_nifti() {
    let Some(data) = common::data_dir("materials from a DICOM series") else {
        return;
    };
    let Some(py) = common::python() else { return };
    let dir = common::temp_dir("materials-dicom");
    let series = data.join("totalseg-example-ct-3d/example_ct_dicom");
    python(
        &py,
        &format!("{HEX_BLOCK}{DICOM_AND_BLOCK}"),
        &[s(&series), s(&dir)],
    );
    let map = |ct: &Path, out: &str| -> atlasmesh::study::MaterialsReport {
        run_ok(&args(&[
            "materials",
            "--mesh",
            &s(&dir.join("block.vtu")),
            "--ct",
            &s(ct),
            "--format",
            "vtu",
            "--no-plots",
            "--out",
            &s(&dir.join(out)),
        ]));
        serde_json::from_slice(&std::fs::read(dir.join(out).join("report.json")).unwrap()).unwrap()
    };
    let dicom = map(&series, "dicom");
    let nifti = map(&dir.join("dicom.nii.gz"), "nifti");
    eprintln!(
        "DICOM series: mean HU {:.2}, NIfTI by SimpleITK {:.2}; range {:?}",
        dicom.materials.mean_hu, nifti.materials.mean_hu, dicom.materials.ct_range
    );
    assert_eq!(dicom.materials.elements, 216);
    assert_eq!(dicom.materials.partly_outside, 0);
    assert!((dicom.materials.mean_hu - nifti.materials.mean_hu).abs() < 1e-3);
    assert!(
        (dicom.materials.modulus_mean - nifti.materials.modulus_mean).abs()
            < 1e-3 * nifti.materials.modulus_mean
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// With nibabel: hexahedra of one voxel whose corners are voxel centres (4 × 4 × 4 in the
/// vertebral body of the spine FE benchmark's density-calibrated L2), written by meshio; with
/// `read`, the materials file atlasmesh wrote read back by meshio and compared with each
/// element's mean density (the trilinear field's mean over such a cell is the mean of its 8
/// corner voxels) and Kopperdahl's law at it.
const DENSITY_BLOCK: &str = r#"
import sys, json, numpy as np, nibabel as nib, meshio
image, seg, out = sys.argv[1], sys.argv[2], sys.argv[3]
im = nib.load(image); v = np.asarray(im.dataobj); s = np.asarray(nib.load(seg).dataobj)
o = np.argwhere(s == 1).mean(0).round().astype(int) - 2
n = 4
g, cells = hex_block(n)
nodes = (im.affine @ np.c_[o + g, np.ones(len(g))].T).T[:, :3]
if np.linalg.det(im.affine[:3, :3]) < 0:
    cells = cells[:, [0, 3, 2, 1, 4, 7, 6, 5]]
if len(sys.argv) > 4:
    m = meshio.read(sys.argv[4])
    means = np.array([v[o[0]+x:o[0]+x+2, o[1]+y:o[1]+y+2, o[2]+z:o[2]+z+2].mean()
                      for x in range(n) for y in range(n) for z in range(n)])
    law = np.maximum(2980.0 * (means / 1000.0) ** 1.05, 1e-4)
    print(json.dumps({
        "density": float(np.abs(m.cell_data["rho_qct"][0] - means / 1000.0).max()),
        "values": float(np.abs(m.cell_data["HU"][0] - means).max()),
        "modulus": float((np.abs(m.cell_data["E"][0] - law) / law).max()),
        "mean": float(means.mean()),
    }))
else:
    meshio.Mesh(nodes, [("hexahedron", cells)]).write(out + "/block.vtu")
"#;

/// An image that holds density already (the spine FE benchmark's L2, K2HPO4 mg/cc): with
/// `image = "density"` and Kopperdahl's law, every element of the materials file (read back
/// by meshio) has the density and modulus that nibabel's voxels give, to 1e-9; no HU check
/// speaks (the image has values from -214 mg/cc, no air, no phantom line).
#[test]
fn an_image_of_density_maps_kopperdahls_law_as_nibabel_reads_it() {
    let Some(data) = common::data_dir("materials from a density image") else {
        return;
    };
    let Some(py) = common::python() else { return };
    let dir = common::temp_dir("materials-density");
    let bench = data.join("spinefe-benchmark-L2");
    let image = bench.join("sub-verse004_0000_vertebra_21_im.nii.gz");
    let seg = bench.join("sub-verse004_0000_vertebra_21_seg.nii.gz");
    let script = format!("{HEX_BLOCK}{DENSITY_BLOCK}");
    python(&py, &script, &[s(&image), s(&seg), s(&dir)]);
    let recipe = dir.join("density.toml");
    std::fs::write(
        &recipe,
        "[calibration]\nimage = \"density\"\nunit = \"mg/cc\"\n\n[modulus]\nlaw = \
         \"kopperdahl-2002-vertebra\"\nfloor = 0.0001\n\n[integration]\nmethod = \"v2\"\n\n\
         [materials]\ngap = 0.0\nmax_materials = 100000\n",
    )
    .unwrap();
    let out = dir.join("out");
    run_ok(&args(&[
        "materials",
        "--mesh",
        &s(&dir.join("block.vtu")),
        "--ct",
        &s(&image),
        "--recipe",
        &s(&recipe),
        "--format",
        "vtu",
        "--no-plots",
        "--out",
        &s(&out),
    ]));
    let report: atlasmesh::study::MaterialsReport =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report.materials.elements, 64);
    assert!(
        report.materials.warnings.is_empty(),
        "{:?}",
        report.materials.warnings
    );
    let theirs: serde_json::Value = serde_json::from_str(&python(
        &py,
        &script,
        &[
            s(&image),
            s(&seg),
            s(&dir),
            s(&out.join("block_materials.vtu")),
        ],
    ))
    .unwrap();
    eprintln!("density image against nibabel: {theirs}");
    assert!(theirs["density"].as_f64().unwrap() < 1e-9, "{theirs}");
    assert!(theirs["values"].as_f64().unwrap() < 1e-6, "{theirs}");
    assert!(theirs["modulus"].as_f64().unwrap() < 1e-9, "{theirs}");
    assert!((report.materials.mean_hu - theirs["mean"].as_f64().unwrap()).abs() < 1e-6);
    std::fs::remove_dir_all(&dir).ok();
}
