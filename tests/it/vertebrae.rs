//! Real CT vertebrae (VerSe L1): raw surfaces in scanner frames, not in correspondence, of
//! different resolutions; one with a floating island, one of genus 2. Leave-one-out as a
//! user runs it (default options, plots on), with landmarks, without, and with the
//! reference surface beside them as the template; every verdict checked against the mesh
//! files written.

use crate::common;
use atlasmesh::geometry::Shape;
use atlasmesh::report::Report;
use std::path::{Path, PathBuf};

struct Vertebrae {
    surfaces: Vec<PathBuf>,
    landmarks: Vec<PathBuf>,
    folder: PathBuf,
}

fn vertebrae(test: &str) -> Option<Vertebrae> {
    let folder = common::data_dir(test)?.join("verse-L1-vertebrae-3d");
    let raw = folder.join("raw");
    let mut surfaces: Vec<PathBuf> = std::fs::read_dir(&raw)
        .unwrap_or_else(|e| panic!("{}: {e}", raw.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    surfaces.sort();
    assert_eq!(surfaces.len(), 10, "10 vertebrae in {}", raw.display());
    let landmarks = surfaces.iter().map(|p| p.with_extension("json")).collect();
    Some(Vertebrae {
        surfaces,
        landmarks,
        folder,
    })
}

/// The subjects as the tool measures them: read, islands dropped.
fn subjects(v: &Vertebrae) -> Vec<Shape<3>> {
    let mut s = atlasmesh::study::load_surfaces(&v.surfaces, &Default::default()).unwrap();
    atlasmesh::study::clean_shapes(&mut s, atlasmesh::study::ISLAND_SHARE);
    s
}

fn loo(v: &Vertebrae, out: &Path, extra: &[&str]) -> Report {
    let mut args: Vec<String> = vec!["loo".into(), "--register".into(), "--shapes".into()];
    args.extend(v.surfaces.iter().map(|p| p.display().to_string()));
    args.extend(extra.iter().map(|s| s.to_string()));
    args.extend(["--out".into(), out.display().to_string()]);
    let o = common::atlasmesh(&args);
    assert!(
        o.status.success(),
        "loo {extra:?}: {}\n{}",
        String::from_utf8_lossy(&o.stderr),
        String::from_utf8_lossy(&o.stdout)
    );
    serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap()
}

/// The figures on one run: 10/10 valid and successful, delivered meshes at a median
/// two-way RMS ≤ 0.4 mm and a 95th percentile (over the subjects) ≤ 2 mm; every success
/// read back from its file; the inputs' topology and registration reported.
fn check(name: &str, r: &Report, out: &Path, subjects: &[Shape<3>], template: Option<&str>) {
    let mut rms: Vec<f64> = r.subjects.iter().map(|s| s.mesh_rms_distance).collect();
    rms.sort_by(f64::total_cmp);
    eprintln!(
        "{name}: {}/{} succeeded, {} valid; delivered RMS median {:.3} mm, max {:.3} mm; \
         instance RMS median {:.4} of the diagonal; mean mesh {} elements of {:.2} mm; template {:?}",
        r.summary.succeeded,
        r.summary.subjects,
        r.summary.meshes_valid,
        r.summary.median_mesh_rms_distance,
        rms.last().copied().unwrap_or(f64::NAN),
        r.summary.median_rms_distance_relative,
        r.mean_mesh.as_ref().unwrap().elements,
        r.mean_mesh.as_ref().unwrap().element_size,
        r.template
    );
    for s in &r.subjects {
        eprintln!(
            "  {}: mesh RMS {:.3} p95 {:.3} max {:.3} mm, {:.1} % beyond one element; \
             instance {:.3} mm; min SJ {:.3}; alpha {}; {:?}",
            s.name,
            s.mesh_rms_distance,
            s.mesh_p95_distance,
            s.mesh_max_distance,
            100.0 * s.mesh_share_beyond_element,
            s.rms_distance,
            s.scaled_jacobian_min,
            s.morph_alpha,
            s.failed_checks
        );
    }
    assert!(r.failed.is_empty(), "{name}: {:?}", r.failed);
    assert_eq!(r.summary.meshes_valid, 10, "{name}");
    assert_eq!(r.summary.succeeded, 10, "{name}");
    // The delivered meshes' aim: a median two-way RMS within 0.4 mm.
    assert!(
        r.summary.median_mesh_rms_distance <= 0.4,
        "{name}: median {}",
        r.summary.median_mesh_rms_distance
    );
    let p95 = rms[(0.95 * (rms.len() - 1) as f64).round() as usize];
    assert!(
        p95 <= 2.0,
        "{name}: 95th percentile of the delivered RMS {p95} mm"
    );
    // Where it matters too: every subject's delivered mesh within one element size of it at
    // its 95th percentile (a boundary fit refused as a whole for one poor region left a
    // vertebra at 1.3 element sizes).
    for s in &r.subjects {
        assert!(
            s.mesh_p95_distance <= s.element_size,
            "{name}: {} at {} mm (95th percentile), elements of {} mm",
            s.name,
            s.mesh_p95_distance,
            s.element_size
        );
    }
    // Success agrees with the delivered mesh, read back from every file.
    assert_eq!(common::assert_delivered(r, out, subjects), 10, "{name}");
    // The inputs: the island of sub-verse010 dropped, the genus of sub-verse024 seen, a
    // residual for every registered shape.
    assert_eq!(r.inputs.len(), 10);
    let input = |stem: &str| r.inputs.iter().find(|i| i.name.starts_with(stem)).unwrap();
    assert_eq!(input("sub-verse010").dropped_components, 1);
    assert_eq!(input("sub-verse010").components, 2);
    assert!(!input("sub-verse010").warnings.is_empty());
    assert_eq!(input("sub-verse024").genus, Some(2));
    assert_eq!(input("sub-verse016").genus, Some(1));
    let registered = r.inputs.iter().filter(|i| i.registration.is_some()).count();
    assert_eq!(registered, if template.is_some() { 10 } else { 9 });
    let t = r.template.as_deref().unwrap();
    match template {
        Some(t0) => assert_eq!(t, t0),
        // The automatic template is never the shape with an island, nor the genus-2 one.
        None => assert!(
            !t.starts_with("sub-verse010") && !t.starts_with("sub-verse024"),
            "{t}"
        ),
    }
    assert!(out.join("report.html").is_file());
}

#[test]
fn vertebrae_leave_one_out_with_landmarks() {
    let Some(v) = vertebrae("vertebrae_leave_one_out_with_landmarks") else {
        return;
    };
    let out = common::temp_dir("vertebrae-landmarks");
    let mut extra = vec!["--landmarks".to_string()];
    extra.extend(v.landmarks.iter().map(|p| p.display().to_string()));
    let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
    let r = loo(&v, &out, &extra);
    check("landmarks", &r, &out, &subjects(&v), None);
    std::fs::remove_dir_all(&out).ok();
}

/// Without landmarks, as a 5-fold cross-validation: each pair of vertebrae (in the order
/// given) fitted with the atlas of the other eight, to the same figures.
#[test]
fn vertebrae_five_fold_without_landmarks() {
    let Some(v) = vertebrae("vertebrae_five_fold_without_landmarks") else {
        return;
    };
    let out = common::temp_dir("vertebrae-plain");
    let r = loo(&v, &out, &["--folds", "5"]);
    assert_eq!(r.folds, Some(5));
    let folds: Vec<Option<usize>> = r.subjects.iter().map(|s| s.fold).collect();
    let expected: Vec<Option<usize>> = (0..10).map(|i| Some(i / 2 + 1)).collect();
    assert_eq!(folds, expected, "consecutive pairs, in the order given");
    check("no landmarks, 5 folds", &r, &out, &subjects(&v), None);
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn vertebrae_leave_one_out_with_the_reference_template() {
    let Some(v) = vertebrae("vertebrae_leave_one_out_with_the_reference_template") else {
        return;
    };
    let out = common::temp_dir("vertebrae-reference");
    let reference = v.folder.join("ref_20.ply").display().to_string();
    let reference_landmarks = v.folder.join("ref_20.json").display().to_string();
    let mut extra = vec![
        "--template".to_string(),
        reference,
        "--template-landmarks".to_string(),
        reference_landmarks,
        "--landmarks".to_string(),
    ];
    extra.extend(v.landmarks.iter().map(|p| p.display().to_string()));
    let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
    let r = loo(&v, &out, &extra);
    check(
        "reference template",
        &r,
        &out,
        &subjects(&v),
        Some("ref_20"),
    );
    std::fs::remove_dir_all(&out).ok();
}
