//! Bones cut by the field of view: label maps of distal femurs whose shaft leaves the image
//! at a different height in each (as knee MR has them), written by nibabel (NIfTI, RAS) and
//! SimpleITK (NRRD, LPS) from the shared femurs voxelized by PyVista (VTK's
//! `vtkPolyDataToImageStencil`), made into one atlas of cut bones.

use crate::common;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The femurs S001.. voxelized at 0.7 × 0.7 × 1 mm, the field of view ending 6 to 24 mm below
/// each shaft's top (and one more at a depth given); even ones written as NIfTI by nibabel,
/// odd ones as NRRD by SimpleITK.
const WRITE_CUT_FEMURS: &str = r#"
import sys, os, numpy as np, meshio, pyvista as pv, nibabel as nib, SimpleITK as sitk
femurs, out, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
# One more femur, S{n + 1}, whose field of view ends this far (mm) below its shaft's top.
extra = [float(a) for a in sys.argv[4:]]
spacing = np.array([0.7, 0.7, 1.0])
for k in range(n + len(extra)):
    name = f"S{k + 1:03d}_Femur"
    m = meshio.read(os.path.join(femurs, name + ".ply"))
    surf = pv.PolyData.from_regular_faces(np.asarray(m.points, float), m.cells_dict["triangle"])
    lo, hi = m.points.min(0) - 3 * spacing, m.points.max(0) + 3 * spacing
    dims = np.ceil((hi - lo) / spacing).astype(int) + 1
    ref = pv.ImageData(dimensions=dims, spacing=spacing, origin=lo)
    mask = surf.voxelize_binary_mask(reference_volume=ref, foreground_value=1)
    vox = np.asarray(mask.point_data["mask"]).reshape(dims[::-1]).astype(np.uint8)  # z, y, x
    top = int((m.points[:, 2].max() - lo[2]) / spacing[2])
    below = extra[0] if k == n else 6 + 18 * k / max(n - 1, 1)
    vox = vox[: top - int(below / spacing[2])]
    if k % 2 == 0:
        affine = np.diag(list(spacing) + [1.0])
        affine[:3, 3] = lo
        data = np.ascontiguousarray(vox.transpose(2, 1, 0))
        nib.save(nib.Nifti1Image(data, affine), os.path.join(out, name + ".nii.gz"))
    else:
        img = sitk.GetImageFromArray(vox)
        img.SetSpacing(tuple(float(s) for s in spacing))
        img.SetOrigin((-float(lo[0]), -float(lo[1]), float(lo[2])))
        img.SetDirection((-1.0, 0, 0, 0, -1.0, 0, 0, 0, 1.0))
        sitk.WriteImage(img, os.path.join(out, name + ".nrrd"), useCompression=True)
"#;

/// Writes `n` cut femur label maps into `dir` ([`WRITE_CUT_FEMURS`]), and one more whose field
/// of view ends `extra` mm below its shaft's top; returns their paths.
fn cut_femurs(py: &Path, data: &Path, dir: &Path, n: usize, extra: Option<f64>) -> Vec<PathBuf> {
    let o = common::run(
        Command::new(py)
            .arg("-c")
            .arg(WRITE_CUT_FEMURS)
            .arg(data.join("knee-distal-femur-synthetic-3d/femur"))
            .arg(dir)
            .arg(n.to_string())
            .args(extra.map(|e| e.to_string())),
        common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (1..=n + usize::from(extra.is_some()))
        .map(|k| {
            let ext = if k % 2 == 1 { "nii.gz" } else { "nrrd" };
            dir.join(format!("S{k:03}_Femur.{ext}"))
        })
        .collect()
}

/// Femur label maps cut by the field of view at six heights make one atlas by default: each
/// cut at the same length from its far end along the shaft (the images' S axis, whichever
/// convention the writer used), closed by a flat cap, and the mean meshed; the cut of each is
/// in the build's facts. A cut along an axis keeps the length asked; a cut that misses, a bad
/// `--cut` and `--cut auto` on closed surfaces are refused naming the shape or the option.
#[test]
fn label_maps_cut_by_the_field_of_view_make_one_atlas_of_cut_bones() {
    let Some(data) = common::data_dir("cut bones") else {
        return;
    };
    let Some(py) = common::python() else {
        return;
    };
    let dir = common::temp_dir("cut-bones");
    // Six to build from, two more to fit, and one cut far below the others.
    let maps = cut_femurs(&py, &data, &dir, 8, Some(45.0));
    let atlas = dir.join("atlas.safetensors");
    let mut args: Vec<String> = vec!["build".into(), "--shapes".into()];
    args.extend(maps[..6].iter().map(|m| m.display().to_string()));
    args.extend(["--label", "1", "--register"].map(String::from));
    let mut with_out = args.clone();
    with_out.extend(["--out".to_string(), atlas.display().to_string()]);
    let o = common::atlasmesh(&with_out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let facts: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("atlas.inputs.json")).unwrap()).unwrap();
    let inputs = facts["inputs"].as_array().unwrap();
    assert_eq!(inputs.len(), 6);
    let lengths: Vec<f64> = inputs
        .iter()
        .map(|i| i["cut"]["length"].as_f64().unwrap())
        .collect();
    for (i, l) in inputs.iter().zip(&lengths) {
        let n: Vec<f64> = serde_json::from_value(i["cut"]["normal"].clone()).unwrap();
        assert!(
            n[2] > 0.999,
            "{}: cut along {n:?}, not the shaft (S)",
            i["name"]
        );
        assert_eq!(*l, lengths[0], "{}: not the common length", i["name"]);
        let removed = i["cut"]["removed_share"].as_f64().unwrap();
        assert!(removed > 0.0 && removed < 0.2, "{}: {removed}", i["name"]);
    }
    // The femurs reach 90 mm and more from the condyles; the shortest field of view leaves 24
    // mm less of the shaft than the tallest: the common length lies below both.
    assert!(lengths[0] > 50.0 && lengths[0] < 90.0, "{}", lengths[0]);
    let q = common::atlasmesh(&[
        "quality".to_string(),
        dir.join("atlas_mean_mesh.vtu").display().to_string(),
    ]);
    assert!(q.status.success(), "{}", String::from_utf8_lossy(&q.stderr));
    // The mean surface is closed (as VTK reads it), and the mean mesh's face on the cut, as
    // meshio reads it: the `CUT` nodes on one plane normal to the shaft, at the top.
    let script = r#"
import sys, json, meshio, numpy as np, pyvista as pv
mean = pv.read(sys.argv[2])
m = meshio.read(sys.argv[1])
cut = m.point_data["set_CUT"] > 0
p = m.points[cut]
centre = p.mean(0)
normal = np.linalg.svd(p - centre)[2][2]
print(json.dumps({"nodes": int(cut.sum()), "off": float(np.abs((p - centre) @ normal).max()),
    "normal_z": float(abs(normal[2])), "below_top": float(m.points[:, 2].max() - centre[2]),
    "open_edges": int(mean.n_open_edges), "triangles": int(mean.n_cells)}))
"#;
    let o = common::run(
        Command::new(&py)
            .arg("-c")
            .arg(script)
            .arg(dir.join("atlas_mean_mesh.vtu"))
            .arg(dir.join("atlas_mean.vtp")),
        common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cut: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let element = facts["mean_mesh"]["element_size"].as_f64().unwrap();
    assert!(
        cut["open_edges"] == 0 && cut["triangles"].as_u64() > Some(1000),
        "the mean surface is open: {cut}"
    );
    assert!(cut["nodes"].as_u64().unwrap() > 200, "{cut}");
    assert!(cut["off"].as_f64().unwrap() < 1e-6 * element, "{cut}");
    assert!(cut["normal_z"].as_f64().unwrap() > 0.999, "{cut}");
    assert!(cut["below_top"].as_f64().unwrap() < 0.5 * element, "{cut}");

    fits_cut_and_whole_subjects(&py, &data, &dir, &atlas, &maps[6..], element);

    // Along an axis: the length asked, for every shape.
    let mut along = args.clone();
    along.extend(["--cut", "S:60", "--no-mesh", "--out"].map(String::from));
    along.push(dir.join("along.safetensors").display().to_string());
    let o = common::atlasmesh(&along);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let along: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("along.inputs.json")).unwrap()).unwrap();
    for i in along["inputs"].as_array().unwrap() {
        assert_eq!(i["cut"]["length"].as_f64(), Some(60.0), "{}", i["name"]);
    }
    // Refusals: a cut beyond the field of view of the shortest (naming the shape), a bad --cut,
    // `--cut auto` on closed surfaces.
    for (cut, expect) in [("S:85", "_Femur: "), ("X:60", "--cut")] {
        let mut bad = args.clone();
        bad.extend(["--cut", cut, "--out"].map(String::from));
        bad.push(dir.join("bad.safetensors").display().to_string());
        let o = common::atlasmesh(&bad);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(expect), "{cut}: {err}");
        assert!(!dir.join("bad.safetensors").exists());
    }
    let femurs = data.join("knee-distal-femur-synthetic-3d/femur");
    let o = common::atlasmesh(&[
        "build".to_string(),
        "--shapes".into(),
        femurs.join("S001_Femur.ply").display().to_string(),
        femurs.join("S002_Femur.ply").display().to_string(),
        "--cut".into(),
        "auto".into(),
        "--out".into(),
        dir.join("closed.safetensors").display().to_string(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("_Femur: --cut auto") && err.contains("closed"),
        "{err}"
    );
}

/// Fits, with the atlas of cut bones, label maps cut by the field of view at other heights (one
/// far below the atlas's cut) and the first of them whole (its closed surface, the shaft going
/// on beyond the atlas's cut), with default options: every one succeeds, its delivered mesh (as
/// meshio reads it) within an element of the subject and its `CUT` face flat to 1e-6 of an
/// element, with the share of the atlas it covers; the cut bone's mesh and the whole bone's
/// agree node by node within a quarter of an element.
fn fits_cut_and_whole_subjects(
    py: &Path,
    data: &Path,
    dir: &Path,
    atlas: &Path,
    maps: &[PathBuf],
    element: f64,
) {
    let whole = data.join("knee-distal-femur-synthetic-3d/femur/S007_Femur.ply");
    let subjects = dir.join("subjects");
    std::fs::create_dir_all(&subjects).unwrap();
    std::fs::copy(&whole, subjects.join("S007_whole.ply")).unwrap();
    let out = dir.join("fit");
    let mut args: Vec<String> = vec!["fit".into(), "--atlas".into(), atlas.display().to_string()];
    args.push("--subjects".into());
    args.extend(maps.iter().map(|m| m.display().to_string()));
    args.push(subjects.join("S007_whole.ply").display().to_string());
    args.extend(["--label", "1", "--no-plots", "--out"].map(String::from));
    args.push(out.display().to_string());
    let o = common::atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let subjects = report["subjects"].as_array().unwrap();
    assert_eq!(subjects.len(), 4);
    for s in subjects {
        assert_eq!(s["success"], true, "{s}");
        let rms = s["mesh_rms_distance"].as_f64().unwrap();
        assert!(rms < element, "{}: delivered RMS {rms}", s["name"]);
        let covered = s["atlas_cut"]["atlas_covered_share"].as_f64().unwrap();
        let beyond = s["atlas_cut"]["beyond_share"].as_f64().unwrap();
        let warned = |w: &str| s["warnings"].to_string().contains(w);
        if s["name"] == "S009_Femur" {
            // 45 mm below the top: short of the atlas's cut by 20 mm and more.
            assert!(covered > 0.6 && covered < 0.95, "{s}");
            assert!(
                beyond == 0.0 && warned("short of the atlas's common cut"),
                "{s}"
            );
        } else {
            assert!(covered > 0.99, "{s}");
        }
        if s["name"] == "S007_whole" {
            assert!(
                beyond > 0.1 && warned("beyond the atlas's common cut"),
                "{s}"
            );
        }
    }
    // The overview says where each subject's mesh ends: the share of the atlas it covers and
    // the share of it beyond the atlas's cut.
    let overview = std::fs::read_to_string(out.join("report.html")).unwrap();
    for s in subjects {
        let cell = format!(
            "covers {:.1} %, {:.1} % beyond",
            100.0 * s["atlas_cut"]["atlas_covered_share"].as_f64().unwrap(),
            100.0 * s["atlas_cut"]["beyond_share"].as_f64().unwrap()
        );
        assert!(overview.contains(&cell), "{}: {cell}", s["name"]);
    }
    let script = r#"
import sys, json, meshio, numpy as np
out = sys.argv[1]
meshes = {n: meshio.read(f"{out}/{n}/{n}_mesh.vtu") for n in ["S007_Femur", "S008_Femur", "S009_Femur", "S007_whole"]}
off = {}
for n, m in meshes.items():
    p = m.points[m.point_data["set_CUT"] > 0]
    c = p.mean(0)
    normal = np.linalg.svd(p - c)[2][2]
    off[n] = float(np.abs((p - c) @ normal).max())
d = np.linalg.norm(meshes["S007_Femur"].points - meshes["S007_whole"].points, axis=1)
print(json.dumps({"off": off, "rms": float(np.sqrt((d ** 2).mean())), "p95": float(np.percentile(d, 95))}))
"#;
    let o = common::run(
        Command::new(py).arg("-c").arg(script).arg(&out),
        common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    eprintln!("cut bones fitted: {m}");
    for (name, off) in m["off"].as_object().unwrap() {
        assert!(
            off.as_f64().unwrap() < 1e-6 * element,
            "{name}: CUT off its plane by {off}"
        );
    }
    assert!(
        m["rms"].as_f64().unwrap() < 0.25 * element,
        "the cut and the whole bone's meshes differ: {m}"
    );
}
