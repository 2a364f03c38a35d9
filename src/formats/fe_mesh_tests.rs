use super::*;
use crate::mesh::ElementKind;

fn tmp(name: &str, text: &str) -> super::outline_tests::TmpFile {
    super::outline_tests::tmp_file("atlasmesh-femesh-", name, text.as_bytes())
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

#[test]
fn a_users_set_named_like_the_whole_mesh_set_is_refused_unless_it_is_the_whole_mesh() {
    let hexes = "*NODE\n1,0,0,0\n2,1,0,0\n3,1,1,0\n4,0,1,0\n5,0,0,1\n6,1,0,1\n7,1,1,1\n8,0,1,1\n\
                 9,2,0,0\n10,2,1,0\n11,2,0,1\n12,2,1,1\n\
                 *ELEMENT, TYPE=C3D8, ELSET=EALL\n1,1,2,3,4,5,6,7,8\n2,2,9,10,3,6,11,12,7\n";
    let path = std::path::Path::new("user.inp");
    // The writer's own whole-mesh sets are not carried as sets.
    let deck = crate::formats::parse_inp(path, hexes).unwrap();
    assert!(deck.mesh.sets.element_sets.is_empty());
    // Abaqus adds the elements of a later `*ELSET, ELSET=EALL` to the set: still the whole.
    assert!(crate::formats::parse_inp(path, &format!("{hexes}*ELSET, ELSET=eall\n2\n")).is_ok());
    // A user's part of the mesh under that name would merge with it when written: refused.
    let part = hexes.replace("ELSET=EALL", "ELSET=SOLID") + "*ELSET, ELSET=EALL\n2\n";
    let e = crate::formats::parse_inp(path, &part)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("user.inp")
            && e.contains("EALL holds 1 of the 2 elements")
            && e.contains("rename"),
        "{e}"
    );
    let mut mesh = deck.mesh.clone();
    mesh.sets.node_sets.insert("NALL".into(), vec![0, 1]);
    assert!(
        mesh.sets
            .check(mesh.kind, 12, 2)
            .unwrap_err()
            .contains("NALL holds 2 of the 12")
    );
}
