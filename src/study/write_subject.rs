//! Writing one subject: its meshes in every format, its deck, its fitted surface and its
//! pictures, beside the measures that [`fit_subject`](super::fit_subject) took.

use super::params::RunParams;
use super::subject::SubjectOutcome;
use crate::error::Result;
use crate::fit::{FitResult, Fitter};
use crate::formats::{write_atomic, write_mesh_with_materials, write_shape};
use crate::geometry::{ClosestPointIndex, Point, Shape, same_dim};
use crate::mesh::{ElementQuality, FeMesh, Morpher};
use crate::model::Atlas;
use crate::report::{SubjectReport, plot_subject};
use std::path::Path;

/// Width of the 3D pictures (pixels): a front and a back view side by side, each cropped to
/// the shape.
const PICTURE_WIDTH: usize = 760;

/// The 3D pictures of a subject (figs. 23 and 27): the fitted surface coloured by its
/// distance to the subject (`distance`, per point; the subject indexed by `index`), the
/// delivered mesh's surface by its own, and the mesh's surface coloured by scaled Jacobian,
/// seen alike; written as `NAME_distance.png`, `NAME_mesh_distance.png`, `NAME_quality.png`
/// into `out`. Returns their names.
fn pictures_3d<const D: usize>(
    atlas: &Atlas<D>,
    subject: &Shape<D>,
    fit: &FitResult<D>,
    (mesh, per_element): (&FeMesh<D>, &[ElementQuality]),
    (distance, index): (&[f64], &ClosestPointIndex<D>),
    out: &Path,
) -> Result<Vec<String>> {
    let base = &file_name(&subject.name);
    let mut files = Vec::new();
    // Figs. 23 and 27: the fitted surface coloured by its distance to the subject, and the
    // morphed mesh's surface coloured by scaled Jacobian, seen alike.
    use crate::report::render;
    let to3 = |v: &[Point<D>]| -> Vec<Point<3>> { v.iter().map(same_dim::<D, 3>).collect() };
    let instance = to3(&fit.instance);
    let tris: Vec<[usize; 3]> = atlas
        .facets
        .iter()
        .map(|f| std::array::from_fn(|k| f[k.min(D - 1)]))
        .collect();
    let view = render::View::fitting(&to3(&subject.points));
    let far = render::distance_scale(distance, subject.bbox_diagonal());
    let by_distance = render::distance_color(far);
    let legend = render::Legend {
        color: &by_distance,
        lo: 0.0,
        hi: far,
        lo_label: "0".into(),
        hi_label: format!("{far:.3} (95th pct.)"),
    };
    // The fitted surface, then the delivered mesh's surface, by their distance to the
    // subject on one scale.
    let picture = |nodes: &[Point<3>], tris: &[[usize; 3]], d: &[f64], what: &str, suffix: &str| {
        let img = render::render_front_back(
            nodes,
            tris,
            Some(d),
            None,
            legend.color,
            &view,
            PICTURE_WIDTH,
        );
        let title = format!(
            "{}: {what}, distance to the subject (front, back)",
            subject.name
        );
        let img = render::annotated(&img, &title, Some(&legend));
        let name = format!("{base}_{suffix}.png");
        write_atomic(&out.join(&name), &img.png()?)?;
        Ok::<_, crate::Error>(name)
    };
    files.push(picture(&instance, &tris, distance, "fit", "distance")?);
    let mesh3 = in_3d_without_sets(mesh);
    let (btris, _) = render::boundary_triangles(&mesh3, &vec![0.0; mesh.num_elements()]);
    let mesh_distance = super::subject_page::boundary_node_distances(mesh, index);
    files.push(picture(
        &mesh3.nodes,
        &btris,
        &mesh_distance,
        "delivered mesh",
        "mesh_distance",
    )?);
    let title = format!(
        "{}: morphed mesh, scaled Jacobian (front, back)",
        subject.name
    );
    let name = format!("{base}_quality.png");
    write_atomic(
        &out.join(&name),
        &quality_picture(mesh, per_element, &view, &title)?,
    )?;
    files.push(name);
    Ok(files)
}

/// `mesh` in 3D coordinates (a 2D mesh at z = 0), its sets left out: what the pictures draw.
fn in_3d_without_sets<const D: usize>(mesh: &FeMesh<D>) -> FeMesh<3> {
    FeMesh {
        nodes: mesh.nodes.iter().map(same_dim::<D, 3>).collect(),
        kind: mesh.kind,
        connectivity: mesh.connectivity.clone(),
        sets: Default::default(),
    }
}

/// The boundary of the volume mesh `mesh` coloured by the scaled Jacobian of its elements
/// (fig. 27), seen by `view`, with `title` and the colour scale: a PNG.
pub(crate) fn quality_picture<const D: usize>(
    mesh: &FeMesh<D>,
    per_element: &[ElementQuality],
    view: &crate::report::render::View,
    title: &str,
) -> Result<Vec<u8>> {
    use crate::report::render;
    let mesh3 = in_3d_without_sets(mesh);
    let sj: Vec<f64> = per_element.iter().map(|e| e.scaled_jacobian_min).collect();
    let (btris, bvals) = render::boundary_triangles(&mesh3, &sj);
    let legend = render::Legend {
        color: &render::jacobian_color,
        lo: 0.0,
        hi: 1.0,
        lo_label: "≤ 0".into(),
        hi_label: "1".into(),
    };
    let img = render::render_front_back(
        &mesh3.nodes,
        &btris,
        None,
        Some(&bvals),
        legend.color,
        view,
        PICTURE_WIDTH,
    );
    render::annotated(&img, title, Some(&legend)).png()
}

/// The 2D picture of a subject (fig. 9): the mean, the subject, the fit's locus and the
/// morphed mesh by scaled Jacobian, written as `NAME.png` into `out`. Returns its name.
fn picture_2d<const D: usize>(
    atlas: &Atlas<D>,
    subject: &Shape<D>,
    fit: &FitResult<D>,
    mesh: &FeMesh<D>,
    base: &str,
    out: &Path,
) -> Result<String> {
    let png = format!("{base}.png");
    let to2 = |v: &[Point<D>]| -> Vec<Point<2>> { v.iter().map(same_dim::<D, 2>).collect() };
    let mean_pts: Vec<Point<2>> = atlas
        .mean
        .iter()
        .map(|p| same_dim::<D, 2>(&fit.similarity.apply(p)))
        .collect();
    let closed = subject.facets.len() == subject.points.len();
    let locus: Vec<Vec<Point<2>>> = fit.locus.iter().map(|l| to2(l)).collect();
    let mesh2 = FeMesh {
        nodes: to2(&mesh.nodes),
        kind: mesh.kind,
        connectivity: mesh.connectivity.clone(),
        sets: Default::default(),
    };
    plot_subject(
        &out.join(&png),
        &subject.name,
        &mean_pts,
        &to2(&subject.points),
        &locus,
        &mesh2,
        closed,
    )?;
    Ok(png)
}

/// [`fit_subject`](super::fit_subject), then [`write_subject`]: one subject fitted, morphed,
/// repaired, measured and written into `out`.
pub fn process_subject<const D: usize>(
    atlas: &Atlas<D>,
    fitter: &Fitter<D>,
    morpher: &Morpher<D>,
    subject: &Shape<D>,
    out: &Path,
    params: &RunParams,
    index_href: &str,
) -> Result<SubjectReport> {
    let outcome = super::fit_subject(atlas, fitter, morpher, subject, params)?;
    write_subject(atlas, subject, outcome, out, params, index_href)
}

/// Writes what [`fit_subject`](super::fit_subject) made of `subject` into `out`: the mesh in
/// every `params.formats` (`NAME_mesh.EXT`, with the mean mesh in the subject's frame beside
/// it for the displacement), the deck (`NAME_deck.inp`), the fitted surface or outline
/// (`NAME_fit.EXT` in every `params.surface_formats`) and, with `params.plots`, its pictures,
/// its thumbnail (`NAME_thumb.png`) and its page (`NAME.html`, linking back to the run's
/// report at `index_href`, relative to `out`). Returns the subject's report with the files
/// written (relative to `out`).
pub fn write_subject<const D: usize>(
    atlas: &Atlas<D>,
    subject: &Shape<D>,
    outcome: SubjectOutcome<D>,
    out: &Path,
    params: &RunParams,
    index_href: &str,
) -> Result<SubjectReport> {
    let SubjectOutcome {
        fit,
        mesh,
        quality: per_element,
        index,
        mut report,
        materials,
    } = outcome;
    let base = file_name(&subject.name);
    let mut files = Vec::new();
    let mean_in_subject = atlas.mesh.moved(&fit.similarity);
    for f in &params.formats {
        let mesh_file = format!("{base}_mesh.{}", f.extension());
        write_mesh_with_materials(
            &out.join(&mesh_file),
            &mesh,
            Some(&mean_in_subject),
            &per_element,
            materials.as_ref(),
        )?;
        files.push(mesh_file);
    }
    if let Some(deck) = &params.deck {
        files.push(deck.write_with_nodes(&mesh.nodes, out, &base)?);
    }
    let fitted = Shape {
        name: subject.name.clone(),
        points: fit.projected.iter().map(|p| p.point).collect(),
        facets: atlas.facets.clone(),
        landmarks: atlas.landmarks.clone(),
    };
    for &f in &params.surface_formats {
        let fit_file = format!("{base}_fit.{}", f.extension());
        write_shape(&out.join(&fit_file), &fitted, f)?;
        files.push(fit_file);
    }
    if params.plots {
        let instance_distance: Vec<f64> = fit
            .instance
            .iter()
            .map(|p| index.closest(p).dist2.sqrt())
            .collect();
        if D == 3 {
            files.extend(pictures_3d(
                atlas,
                subject,
                &fit,
                (&mesh, &per_element),
                (&instance_distance, &index),
                out,
            )?);
        } else {
            files.push(picture_2d(atlas, subject, &fit, &mesh, &base, out)?);
        }
        // The index's thumbnail: the mesh (3D) or the subject's picture (2D), 200 pixels wide.
        let thumb_source = files.iter().rev().find(|f| f.ends_with(".png")).cloned();
        if let Some(m) = &materials {
            let name = format!("{base}_E.png");
            crate::report::plot_modulus_histogram(
                &out.join(&name),
                &m.summary.histogram,
                &format!(
                    "{}: Young's modulus of the elements from the CT",
                    subject.name
                ),
            )?;
            files.push(name);
        }
        if let Some(f) = thumb_source {
            let bytes =
                std::fs::read(out.join(&f)).map_err(|e| crate::Error::io(out.join(&f), e))?;
            let name = format!("{base}_thumb.png");
            write_atomic(
                &out.join(&name),
                &crate::report::render::thumbnail(&bytes, 200)?,
            )?;
            files.push(name);
        }
        // The page last: it links every file above.
        report.files = files;
        let page = super::subject_page::PageInputs {
            atlas,
            subject,
            fit: &fit,
            mesh: &mesh,
            per_element: &per_element,
            index: &index,
            mean_in_subject: &mean_in_subject,
            instance_distance: &instance_distance,
            materials: materials.as_ref(),
        };
        let name = super::subject_page::write_page(&page, &report, &base, out, index_href)?;
        report.files.push(name);
        return Ok(report);
    }
    report.files = files;
    Ok(report)
}

/// A subject's name as a safe file or folder name: ASCII letters, digits, `-`, `_` and `.`
/// kept, anything else (separators, spaces, controls) `_`; never empty, never starting with
/// a dot (so never `.`, `..` or a hidden name); at most [`MAX_FILE_STEM`] bytes.
pub(crate) fn file_name(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.starts_with('.') || s.is_empty() {
        s.insert(0, '_');
    }
    // A file system takes 255 bytes a name: a long name keeps its start and a checksum of
    // the whole, so that two long names stay apart and `NAME_thumb.png` still fits.
    if s.len() > MAX_FILE_STEM {
        let crc = crc32fast::hash(name.as_bytes());
        s.truncate(MAX_FILE_STEM - 9);
        s.push_str(&format!("~{crc:08x}"));
    }
    s
}

/// The longest file or folder name made from a subject's name (bytes), room left for the
/// suffixes of its files.
pub(crate) const MAX_FILE_STEM: usize = 120;

#[cfg(test)]
mod tests {
    #[test]
    fn long_names_are_cut_with_a_checksum() {
        let a = "a".repeat(240);
        let b = format!("{}b", "a".repeat(239));
        let (fa, fb) = (super::file_name(&a), super::file_name(&b));
        assert_eq!(fa.len(), super::MAX_FILE_STEM);
        assert_ne!(fa, fb);
        assert_eq!(super::file_name("S 1/x"), "S_1_x");
    }
}
