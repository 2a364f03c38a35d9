use super::*;
use crate::mesh::ElementKind;

fn tmp(name: &str, text: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("atlasmesh-femesh-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn bad_gmsh_and_abaqus_files_are_errors_not_panics() {
    let head = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";
    for (name, elements) in [
        ("neg.msh", "$Elements\n1\n1 4 -5 1 2 3 4\n$EndElements\n"),
        (
            "huge.msh",
            "$Elements\n1\n1 4 99999999 1 2 3 4\n$EndElements\n",
        ),
        ("node.msh", "$Elements\n1\n1 4 0 1 2 3 9\n$EndElements\n"),
        ("count.msh", "$Elements\n5\n1 4 0 1 2 3 4\n$EndElements\n"),
    ] {
        let p = tmp(name, &format!("{head}{elements}"));
        let e = read_fe_mesh::<3>(&p).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
    let ok = tmp(
        "ok.msh",
        &format!("{head}$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n"),
    );
    let m = read_fe_mesh::<3>(&ok).unwrap();
    assert_eq!(m.kind, ElementKind::Tet4);
    for (name, text) in [
        (
            "gen.inp",
            "*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=C3D4\n1, 1, 1, 1, 1\n*NSET, NSET=A, GENERATE\n5, 1, 1\n",
        ),
        (
            "short.inp",
            "*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=C3D8\n1, 1, 1\n",
        ),
        ("nan.inp", "*NODE\n1, nan, 0, 0\n"),
        (
            "surf.inp",
            "*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=C3D4\n1, 1, 1, 1, 1\n*SURFACE, NAME=S\n1, S9\n",
        ),
    ] {
        let p = tmp(name, text);
        let e = read_fe_mesh::<3>(&p).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
}
