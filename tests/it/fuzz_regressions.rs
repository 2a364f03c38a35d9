//! Every input that crashed a fuzz target (`fuzz/regressions/TARGET/*`), run through the same
//! readers as the target: each must give a result or an error, never a panic.

use crate::common;

use std::path::Path;

fn run(target: &str, data: &[u8], dir: &Path) {
    let file = |ext: &str| {
        let p = dir.join(format!("input.{ext}"));
        std::fs::write(&p, data).unwrap();
        p
    };
    match target {
        "csv" => {
            let p = file("csv");
            let _ = atlasmesh::formats::read_outlines(&p, false);
            let _ = atlasmesh::formats::landmarks::read_landmarks_csv::<2>(&p);
            let _ = atlasmesh::formats::landmarks::read_landmarks_csv::<3>(&p);
        }
        "text" => {
            let _ = atlasmesh::formats::read_outlines(&file("txt"), true);
        }
        "ply" | "stl" | "obj" | "vtp" => {
            let _ = atlasmesh::formats::read_surface(&file(target));
        }
        "vtk" => {
            let p = file("vtk");
            let _ = atlasmesh::formats::read_surface(&p);
            let _ = atlasmesh::formats::read_outlines(&p, true);
            let _ = atlasmesh::formats::read_fe_mesh_raw(&p);
        }
        "vtu" | "msh" | "inp" => {
            let _ = atlasmesh::formats::read_fe_mesh_raw(&file(target));
        }
        "landmarks" => {
            for ext in ["json", "pts"] {
                let p = file(ext);
                let _ = atlasmesh::formats::landmarks::read_landmarks::<2>(&p);
                let _ = atlasmesh::formats::landmarks::read_landmarks::<3>(&p);
            }
        }
        "sets" => {
            let _ = atlasmesh::mesh::sets::SetsConfig::read(&file("toml"));
        }
        "atlas" => {
            let p = file("safetensors");
            let _ = atlasmesh::model::Atlas::<2>::load(&p);
            let _ = atlasmesh::model::Atlas::<3>::load(&p);
        }
        "dicom" => {
            // The bytes as the one file of a DICOM folder.
            let folder = dir.join("dicom");
            std::fs::create_dir_all(&folder).unwrap();
            std::fs::write(folder.join("input.dcm"), data).unwrap();
            let _ = atlasmesh::formats::dicom_series::read_dicom_series(&folder);
        }
        other => panic!("no reader for fuzz target {other}"),
    }
}

#[test]
fn inputs_that_crashed_a_fuzz_target_are_handled() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions");
    let dir = common::temp_dir("fuzz-regressions");
    let mut n = 0;
    for target in std::fs::read_dir(&root).unwrap().flatten() {
        let name = target.file_name().to_string_lossy().into_owned();
        for input in std::fs::read_dir(target.path()).unwrap().flatten() {
            let data = std::fs::read(input.path()).unwrap();
            run(&name, &data, &dir);
            n += 1;
        }
    }
    assert!(n >= 1, "no regression inputs found in {}", root.display());
    std::fs::remove_dir_all(&dir).ok();
}
