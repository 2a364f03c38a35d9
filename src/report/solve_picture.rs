//! The picture of a solved model: its boundary coloured by the displacement's magnitude.

use crate::error::Result;
use crate::mesh::FeMesh;

use super::render;

/// Width of the picture (pixels): a front and a back view side by side.
const WIDTH: usize = 760;

/// The boundary of `mesh` (world, mm) coloured by the magnitude of the nodal displacements
/// `u` (mm; NaN for a node without one: grey), seen from the side with world axis `up` (the
/// load's axis, 0-2) vertical, front and back, with `title` and the scale from 0 to the
/// largest magnitude: a PNG.
///
/// # Errors
/// Those of encoding the PNG.
pub fn displacement_picture(
    mesh: &FeMesh<3>,
    u: &[[f64; 3]],
    up: usize,
    title: &str,
) -> Result<Vec<u8>> {
    let magnitude: Vec<f64> = (0..mesh.nodes.len())
        .map(|n| {
            u.get(n).map_or(f64::NAN, |v| {
                (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
            })
        })
        .collect();
    let largest = magnitude
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let (tris, _) = render::boundary_triangles(mesh, &[]);
    let mut axis = [0.0; 3];
    axis[up.min(2)] = 1.0;
    let view = render::View::upright(&mesh.nodes, axis);
    let color = render::distance_color(largest);
    let legend = render::Legend {
        color: &color,
        lo: 0.0,
        hi: largest,
        lo_label: "0".into(),
        hi_label: format!("{largest:.3} mm"),
    };
    let img = render::render_front_back(
        &mesh.nodes,
        &tris,
        Some(&magnitude),
        None,
        legend.color,
        &view,
        WIDTH,
    );
    render::annotated(&img, title, Some(&legend)).png()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube compressed along z: the top's nodes move, the picture shows the top red
    /// and the bottom blue, seen with z up.
    #[test]
    fn the_moving_face_is_red_and_up() {
        let mesh = crate::mesh::HexMesh::block(1);
        let u: Vec<[f64; 3]> = (0..8)
            .map(|n| [0.0, 0.0, if n >= 4 { -0.2 } else { 0.0 }])
            .collect();
        let png = displacement_picture(&mesh, &u, 2, "cube").unwrap();
        let img = image_rows(&png);
        // Down the middle of the front view (left of the colour bar; the title's text is
        // grey): the topmost coloured pixel red, the lowest blue.
        let x = img[0].len() / 4;
        let coloured: Vec<[u8; 3]> = img
            .iter()
            .map(|row| row[x])
            .filter(|p| p[0] != p[2] && *p != [255, 255, 255])
            .collect();
        let (top, bottom) = (coloured[0], coloured[coloured.len() - 1]);
        assert!(top[0] > top[2], "top {top:?}");
        assert!(bottom[2] > bottom[0], "bottom {bottom:?}");
    }

    /// The RGB rows of a PNG.
    fn image_rows(png: &[u8]) -> Vec<Vec<[u8; 3]>> {
        let decoder = png::Decoder::new(std::io::Cursor::new(png));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        let channels = info.color_type.samples();
        buf[..info.buffer_size()]
            .chunks(info.line_size)
            .map(|row| {
                row.chunks(channels)
                    .take(info.width as usize)
                    .map(|p| [p[0], p[1], p[2]])
                    .collect()
            })
            .collect()
    }
}
