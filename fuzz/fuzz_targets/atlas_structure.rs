#![no_main]
// Structure-aware atlas fuzzing: the fuzz input edits a valid atlas's tensors (values,
// lengths, indices, the element kind), the file is written again with a right checksum, and
// the loader must refuse the inconsistent ones without panicking or hanging.
use atlasmesh::mesh::ElementKind;
use atlasmesh::model::Atlas;
use std::sync::OnceLock;

fn seed() -> &'static Atlas<2> {
    static SEED: OnceLock<Atlas<2>> = OnceLock::new();
    SEED.get_or_init(|| {
        let bytes = include_bytes!("../seeds/atlas/demo2d.safetensors");
        Atlas::<2>::from_bytes(&atlasmesh_fuzz::name("safetensors"), bytes).expect("seed atlas")
    })
}

const KINDS: [ElementKind; 6] = [
    ElementKind::Quad4,
    ElementKind::Tri3,
    ElementKind::Hex8,
    ElementKind::Tet4,
    ElementKind::Hex20,
    ElementKind::Tet10,
];

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let mut a = seed().clone();
    // Edits of 11 bytes: what, where (u16), a value (f64 bits).
    for e in data.chunks_exact(11) {
        let at = u16::from_le_bytes([e[1], e[2]]) as usize;
        let v = f64::from_le_bytes(e[3..11].try_into().unwrap());
        let i = v.to_bits() as usize;
        match e[0] % 12 {
            0 if !a.mean.is_empty() => {
                let k = at % a.mean.len();
                a.mean[k][at % 2] = v;
            }
            1 if !a.eigenvalues.is_empty() => {
                let k = at % a.eigenvalues.len();
                a.eigenvalues[k] = v;
            }
            2 if !a.cumulative_variance.is_empty() => {
                let k = at % a.cumulative_variance.len();
                a.cumulative_variance[k] = v;
            }
            3 if !a.mesh.nodes.is_empty() => {
                let k = at % a.mesh.nodes.len();
                a.mesh.nodes[k][at % 2] = v;
            }
            4 if !a.mesh.connectivity.is_empty() => {
                let k = at % a.mesh.connectivity.len();
                a.mesh.connectivity[k] = i % (a.mesh.nodes.len() + 2);
            }
            5 if !a.facets.is_empty() => {
                let k = at % a.facets.len();
                a.facets[k][at % 2] = i % (a.mean.len() + 2);
            }
            6 => a.mesh.kind = KINDS[at % KINDS.len()],
            7 => a.eigenvalues.truncate(at),
            8 => a.cumulative_variance.truncate(at),
            9 => a.mesh.connectivity.truncate(at),
            10 => a.facets.truncate(at),
            _ => a.landmarks.push(i % (a.mean.len() + 2)),
        }
    }
    if let Ok(bytes) = a.to_bytes() {
        let _ = Atlas::<2>::from_bytes(&atlasmesh_fuzz::name("safetensors"), &bytes);
    }
});
