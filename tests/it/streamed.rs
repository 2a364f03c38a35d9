//! `atlasmesh build --stream`: the atlas of a cohort read from its files on each pass (GPA in
//! passes, the leading modes by a randomized PCA) against the in-memory build of the same 30
//! real femurs; its mean mesh read back by meshio and a femur fitted with it; what it refuses.

use crate::bad_input::fails;
use crate::common::{self, atlasmesh};
use atlasmesh::model::Atlas;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn femur_files(data: &Path) -> Vec<PathBuf> {
    (1..=30)
        .map(|k| {
            data.join(format!(
                "knee-distal-femur-synthetic-3d/femur/S{k:03}_Femur.ply"
            ))
        })
        .collect()
}

fn build(args: &[String]) -> String {
    let o = atlasmesh(args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// `|a · b|` of mode `k` of two atlases (unit columns): 1 for the same mode up to its sign.
fn alignment(a: &Atlas<3>, b: &Atlas<3>, k: usize) -> f64 {
    (0..a.modes.nrows())
        .map(|r| a.modes[(r, k)] * b.modes[(r, k)])
        .sum::<f64>()
        .abs()
}

/// 30 femurs in correspondence, 15 modes asked (25 directions sampled of the 29 modes), read
/// 7 at a time from a `.list`: the streamed model is the in-memory one (mean, the data frame,
/// the eigenvalues and the share of variance of every mode kept, the modes up to their sign).
#[test]
fn a_streamed_atlas_of_femurs_is_the_in_memory_one() {
    let Some(data) = common::data_dir("a_streamed_atlas_of_femurs_is_the_in_memory_one") else {
        return;
    };
    let d = common::temp_dir("streamed");
    let files = femur_files(&data);
    let list = d.join("femurs.list");
    let text: Vec<String> = files.iter().map(|f| s(f)).collect();
    std::fs::write(&list, text.join("\n")).unwrap();
    let dense = d.join("dense.safetensors");
    let streamed = d.join("streamed.safetensors");
    let mut args: Vec<String> = ["build", "--no-mesh", "--modes", "15", "--shapes"]
        .map(String::from)
        .to_vec();
    args.push(s(&list));
    let mut a = args.clone();
    a.extend(["--out".into(), s(&dense)]);
    build(&a);
    let mut a = args.clone();
    a.extend(["--stream", "--batch", "7", "--out"].map(String::from));
    a.push(s(&streamed));
    let said = build(&a);
    assert!(
        said.contains("30 shapes") && said.contains("15 modes"),
        "{said}"
    );
    let (x, y) = (
        Atlas::<3>::load(&dense).unwrap(),
        Atlas::<3>::load(&streamed).unwrap(),
    );
    assert_eq!(y.training_shapes, 30);
    assert_eq!((x.mean.len(), y.num_modes()), (y.mean.len(), 15));
    let apart = x
        .mean
        .iter()
        .zip(&y.mean)
        .map(|(p, q)| atlasmesh::geometry::dist2(*p, *q).sqrt())
        .fold(0.0, f64::max);
    assert!(apart < 1e-12, "means {apart} apart (reference frame)");
    let (fx, fy) = (x.data_frame.unwrap(), y.data_frame.unwrap());
    assert!((fx.s / fy.s - 1.0).abs() < 1e-12);
    let mut worst = (0.0f64, 0.0f64);
    for k in 0..15 {
        let rel = (y.eigenvalues[k] / x.eigenvalues[k] - 1.0).abs();
        let cos = 1.0 - alignment(&x, &y, k);
        worst = (worst.0.max(rel), worst.1.max(cos));
        assert!(rel < 1e-6, "mode {}: eigenvalue off by {rel}", k + 1);
        assert!(cos < 1e-6, "mode {}: 1 - |cos| {cos}", k + 1);
        let share = (x.cumulative_variance[k] - y.cumulative_variance[k]).abs();
        assert!(
            share < 1e-9,
            "mode {}: share of variance off by {share}",
            k + 1
        );
    }
    eprintln!(
        "streamed femur model: eigenvalues within {:.1e}, modes within {:.1e} (1 - |cos|)",
        worst.0, worst.1
    );
}

/// The streamed atlas with default options (a share of variance kept, within the modes
/// computed; the automatic mean mesh): the mesh written beside it read back by meshio,
/// element for element, and a femur fitted with it (`fit`'s defaults) successfully, its
/// delivered mesh read back against its verdict.
#[test]
fn a_streamed_atlas_meshes_its_mean_and_fits_a_femur() {
    let Some(data) = common::data_dir("a_streamed_atlas_meshes_its_mean_and_fits_a_femur") else {
        return;
    };
    let d = common::temp_dir("streamed-mesh");
    let files = femur_files(&data);
    let atlas = d.join("femur.safetensors");
    let mut args: Vec<String> = ["build", "--stream"].map(String::from).to_vec();
    args.extend(["--out".into(), s(&atlas), "--shapes".into()]);
    args.extend(files[..29].iter().map(|f| s(f)));
    let said = build(&args);
    assert!(
        said.contains("29 shapes") && said.contains("hex8"),
        "{said}"
    );
    let model = Atlas::<3>::load(&atlas).unwrap();
    assert!(model.has_mesh());
    assert!(model.cumulative_variance[model.num_modes() - 1] >= 0.985);
    if let Some(py) = common::python() {
        let o = std::process::Command::new(py)
            .args([
                "-c",
                "import sys, meshio; m = meshio.read(sys.argv[1]); print(sum(len(c.data) for c in m.cells if c.type == 'hexahedron'))",
            ])
            .arg(d.join("femur_mean_mesh.vtu"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let hexes: usize = String::from_utf8_lossy(&o.stdout).trim().parse().unwrap();
        assert_eq!(hexes, model.mesh.num_elements());
    }
    let out = d.join("fit");
    let o = atlasmesh(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subjects",
        &s(&files[29]),
        "--out",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert!(
        report.subjects[0].success,
        "{:?}",
        report.subjects[0].failed_checks
    );
    assert_eq!(
        common::assert_delivered(&report, &out, &common::femurs(&data)[29..]),
        1
    );
}

/// A surface of another point count in the cohort, a share of variance the modes computed do
/// not reach, a label map: refused with the file and the way out, nothing written.
#[test]
fn a_streamed_atlas_refuses_what_it_cannot_model() {
    let Some(data) = common::data_dir("a_streamed_atlas_refuses_what_it_cannot_model") else {
        return;
    };
    let d = common::temp_dir("streamed-bad");
    let mut files = femur_files(&data);
    files[3] = data.join("verse-L1-vertebrae-3d/raw/sub-verse013_segment_20.ply");
    let atlas = d.join("bad.safetensors");
    let mut args: Vec<String> = ["build", "--stream", "--no-mesh", "--out"]
        .map(String::from)
        .to_vec();
    args.push(s(&atlas));
    args.push("--shapes".into());
    args.extend(files.iter().map(|f| s(f)));
    fails(
        &atlasmesh(&args),
        2,
        &["sub-verse013_segment_20.ply", "point correspondence"],
    );
    let mut args: Vec<String> = [
        "build",
        "--stream",
        "--no-mesh",
        "--max-modes",
        "2",
        "--out",
    ]
    .map(String::from)
    .to_vec();
    args.push(s(&atlas));
    args.push("--shapes".into());
    args.extend(femur_files(&data).iter().map(|f| s(f)));
    fails(&atlasmesh(&args), 2, &["--max-modes", "2 leading modes"]);
    let seg = data.join("spinefe-benchmark-L2/sub-verse004_0000_vertebra_21_seg.nii.gz");
    fails(
        &atlasmesh(&[
            "build",
            "--stream",
            "--out",
            &s(&atlas),
            "--shapes",
            &s(&seg),
        ]),
        2,
        &["label map", "atlasmesh register"],
    );
    assert!(!atlas.exists());
    assert!(crate::bad_input::files_in(&d).is_empty());
}
