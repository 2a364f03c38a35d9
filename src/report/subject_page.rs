//! A subject's own page, `NAME.html` beside its files: its verdict and warnings, the
//! interactive view of its surface, fit and mesh, its pictures, its measures, its `E_d`
//! against the iterations, its worst elements and its files, linked.

use super::SubjectReport;
use super::html::{STYLE, escape, num};
use super::viewer::{Scene, VIEWER_SCRIPT, VIEWER_STYLE, viewer_html};
use crate::error::Result;
use crate::geometry::Point;
use std::fmt::Write as _;
use std::path::Path;

/// An element of the mesh written, among those of the smallest scaled Jacobian.
#[derive(Clone, Debug, PartialEq)]
pub struct WorstElement {
    /// Its number in the mesh files (1-based, as in `.inp`, `.msh` and `.feb`).
    pub id: usize,
    /// Its smallest corner scaled Jacobian.
    pub scaled_jacobian: f64,
    /// The mean of its corners (the subject's frame and unit).
    pub position: Point<3>,
}

/// What a subject's page shows besides its report.
pub struct SubjectPage<'a> {
    /// The subject's measures (files relative to the page's folder).
    pub report: &'a SubjectReport,
    /// 2 or 3.
    pub dimension: usize,
    /// The interactive view.
    pub scene: &'a Scene,
    /// The worst elements, worst first.
    pub worst: &'a [WorstElement],
    /// The link back to the run's `report.html`, relative to the page.
    pub index_href: &'a str,
}

/// The edge ratio above which a subject's page flags its mesh: mesh checks commonly flag
/// elements whose aspect ratio exceeds 10.
const EDGE_RATIO_FLAG: f64 = 10.0;

/// What the user should know of a subject beside its verdict: its warnings, a stiffened
/// morph, a repair, elements under the usual bound, a large edge ratio, an unconverged fit
/// (HTML, escaped).
fn notes(r: &SubjectReport) -> Vec<String> {
    let mut notes: Vec<String> = r.warnings.iter().map(|w| escape(w)).collect();
    if r.morph_escalated {
        notes.push(format!(
            "The morph stiffened to alpha {} to keep every element valid.",
            num(r.morph_alpha, 0)
        ));
    }
    if r.repaired {
        notes.push(format!(
            "Repaired: elements were below the scaled Jacobian bound {} (smallest before {}, after {}); boundary nodes moved off the subject by at most {} ({} edge lengths).",
            num(r.repair_bound, 2),
            num(r.scaled_jacobian_min_before_repair, 3),
            num(r.scaled_jacobian_min, 3),
            num(r.surface_distance_change, 4),
            num(r.surface_distance_change_edges, 2)
        ));
    }
    if r.elements_below_bound > 0 {
        notes.push(format!(
            "{} elements are below the usual acceptance bound of their kind (scaled Jacobian \
             0.5 for hexahedra, 0.3 for quadrilaterals, 0.2 for simplices), which the checks \
             above do not require; the view outlines the worst of them.",
            r.elements_below_bound
        ));
    }
    if r.edge_ratio_max > EDGE_RATIO_FLAG {
        notes.push(format!(
            "The largest edge ratio (longest edge over shortest of one element) is {}: above \
             {EDGE_RATIO_FLAG}, where mesh checks usually flag an element.",
            num(r.edge_ratio_max, 1)
        ));
    }
    if !r.converged {
        notes.push("The last inner loop of Algorithm 1 did not meet its tolerance.".into());
    }
    notes
}

/// Writes the page of `page` to `path`.
pub fn write_subject_page(path: &Path, page: &SubjectPage) -> Result<()> {
    let r = page.report;
    let mut h = String::with_capacity(1 << 16);
    let title = format!("atlasmesh: subject {}", r.name);
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>{STYLE}{VIEWER_STYLE}</style></head>\n<body>\n<p class=\"meta\"><a href=\"{}\">← the run's report</a></p>\n<h1>{}</h1>",
        escape(&title),
        escape(page.index_href),
        escape(&title)
    );
    // The verdict, and what the user should know.
    let _ = writeln!(
        h,
        "<p class=\"verdict {}\">{}</p>",
        if r.success { "ok" } else { "bad" },
        if r.success {
            format!(
                "Every check passed: the mesh is within its distance bound of the subject and \
                 no farther than the fitted instance, no element is inverted and every \
                 element's scaled Jacobian is at or above the repair bound {}.",
                num(r.repair_bound, 2)
            )
        } else {
            format!("Checks failed: {}.", escape(&r.failed_checks.join(", ")))
        }
    );
    let notes = notes(r);
    if !notes.is_empty() {
        h.push_str("<ul class=\"warnings\">");
        for n in &notes {
            let _ = write!(h, "<li>{n}</li>");
        }
        h.push_str("</ul>\n");
    }
    h.push_str("<h2>View</h2>\n<p class=\"hint\">Drag to rotate, right-drag (or shift-drag) to pan, the wheel to zoom. The worst elements are outlined in magenta, inside the volume too; clip to look at them.</p>\n");
    h.push_str(&viewer_html(page.scene, "scene", 760, 520));
    let pictures: Vec<&String> = r
        .files
        .iter()
        .filter(|f| f.ends_with(".png") && !f.ends_with("_thumb.png"))
        .collect();
    if !pictures.is_empty() {
        h.push_str("<div class=\"figs\">");
        for f in pictures {
            let _ = write!(
                h,
                "<figure><img class=\"fig\" src=\"{}\" alt=\"{}\"></figure>",
                escape(f),
                escape(f)
            );
        }
        h.push_str("</div>\n");
    }
    measures(&mut h, r);
    if let Some(m) = &r.materials {
        materials(&mut h, m);
    }
    h.push_str("<h2>E_d per iteration (eq. 6)</h2>\n");
    h.push_str(&e_d_svg(&r.e_d_history, 560.0, 220.0));
    worst(&mut h, page);
    h.push_str("<h2>Files</h2>\n<ul class=\"files\">");
    for f in r
        .files
        .iter()
        .filter(|f| !f.ends_with(".png") && !f.ends_with(".html"))
    {
        let _ = write!(h, "<li><a href=\"{}\">{}</a></li>", escape(f), escape(f));
    }
    h.push_str("</ul>\n");
    let _ = write!(
        h,
        "<script>{}</script>\n<script>{VIEWER_SCRIPT}</script>\n</body></html>\n",
        super::html::SCRIPT
    );
    crate::formats::write_atomic(path, h.as_bytes())
}

fn measures(h: &mut String, r: &SubjectReport) {
    let mut rows: Vec<(&str, String)> = vec![
        (
            "mesh RMS distance to the subject",
            num(r.mesh_rms_distance, 4),
        ),
        (
            "mesh RMS distance / diagonal",
            num(r.mesh_rms_distance_relative, 5),
        ),
        ("mesh 95th-percentile distance", num(r.mesh_p95_distance, 4)),
        ("mesh largest distance", num(r.mesh_max_distance, 4)),
        (
            "subject points beyond one element",
            format!("{} %", num(100.0 * r.mesh_share_beyond_element, 2)),
        ),
        ("element size", num(r.element_size, 4)),
        ("fit: two-way RMS distance", num(r.rms_distance, 4)),
        (
            "fit: RMS distance / diagonal",
            num(r.rms_distance_relative, 5),
        ),
        ("fit: E_d (eq. 6)", num(r.e_d, 6)),
        ("fit: iterations", r.iterations.to_string()),
        ("fit: time", format!("{} ms", num(r.fit_seconds * 1e3, 1))),
        ("normal correlation (eq. 13)", num(r.normal_correlation, 4)),
        ("smallest scaled Jacobian", num(r.scaled_jacobian_min, 3)),
        (
            "1st / 5th percentile scaled Jacobian",
            format!(
                "{} / {}",
                num(r.scaled_jacobian_p01, 3),
                num(r.scaled_jacobian_p05, 3)
            ),
        ),
        ("inverted elements", r.inverted_elements.to_string()),
        (
            "inverted before repair",
            r.inverted_before_repair.to_string(),
        ),
        ("largest edge ratio", num(r.edge_ratio_max, 2)),
        ("morph alpha (eq. 9)", num(r.morph_alpha, 1)),
    ];
    if let Some(v) = r.voxel_size.filter(|v| *v > 0.0) {
        // A label map's subject: the same distances in its voxels.
        let at = rows.len().min(4);
        rows.splice(
            at..at,
            [
                ("voxel size (label map)", num(v, 4)),
                (
                    "mesh RMS distance in voxels",
                    num(r.mesh_rms_distance / v, 3),
                ),
                (
                    "mesh 95th-percentile distance in voxels",
                    num(r.mesh_p95_distance / v, 3),
                ),
            ],
        );
    }
    h.push_str("<h2>Measures</h2>\n<p class=\"hint\">Lengths in the subject's unit.</p>\n<table class=\"measures\"><tbody>");
    for (k, v) in rows {
        let _ = write!(h, "<tr><td>{}</td><td>{v}</td></tr>", escape(k));
    }
    if let Some(c) = &r.atlas_cut {
        let _ = write!(
            h,
            "<tr><td>the atlas's common cut</td><td>the mesh ends on the plane through ({}) normal to ({}); the subject covers {} % of the atlas's surface, {} % of its own lies beyond the cut</td></tr>",
            c.point
                .iter()
                .map(|x| num(*x, 2))
                .collect::<Vec<_>>()
                .join(", "),
            c.normal
                .iter()
                .map(|x| num(*x, 3))
                .collect::<Vec<_>>()
                .join(", "),
            num(100.0 * c.atlas_covered_share, 1),
            num(100.0 * c.beyond_share, 1)
        );
    }
    if let Some(m) = r.mirrored_rms_distance {
        let _ = write!(
            h,
            "<tr><td>fit of the mirror image: RMS distance</td><td>{}</td></tr>",
            num(m, 4)
        );
    }
    h.push_str("</tbody></table>\n");
}

fn worst(h: &mut String, page: &SubjectPage) {
    if page.worst.is_empty() {
        return;
    }
    let _ = writeln!(
        h,
        "<h2>The {} worst elements</h2>\n<p class=\"hint\">By smallest corner scaled Jacobian; numbers as in the mesh files. Click a row to look at it.</p>\n<table class=\"worst\"><thead><tr><th>element</th><th>scaled Jacobian</th><th>position (x, y{})</th></tr></thead><tbody>",
        page.worst.len(),
        if page.dimension == 3 { ", z" } else { "" }
    );
    for w in page.worst {
        let p = &w.position[..page.dimension];
        let _ = writeln!(
            h,
            "<tr data-focus=\"{}\"><td>{}</td><td>{}</td><td>{}</td></tr>",
            w.position
                .iter()
                .map(|x| format!("{x:.6}"))
                .collect::<Vec<_>>()
                .join(","),
            w.id,
            num(w.scaled_jacobian, 3),
            p.iter().map(|x| num(*x, 3)).collect::<Vec<_>>().join(", ")
        );
    }
    h.push_str("</tbody></table>\n");
}

/// `E_d` against the iterations as an inline SVG plot (`width × height`), log scale, with
/// axes, integer iteration ticks and the first and last values labelled.
pub fn e_d_svg(history: &[f64], width: f64, height: f64) -> String {
    let pts: Vec<(usize, f64)> = history
        .iter()
        .enumerate()
        .filter(|(_, v)| v.is_finite() && **v > 0.0)
        .map(|(i, v)| (i, v.log10()))
        .collect();
    if pts.len() < 2 {
        return "<p class=\"hint\">(fewer than two iterations)</p>".into();
    }
    let (l, r, t, b) = (64.0, 16.0, 12.0, 36.0);
    let (lo, hi) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.1), a.1.max(p.1))
    });
    let (lo, hi) = (lo.floor(), hi.ceil().max(lo.floor() + 1.0));
    let last = pts.last().map_or(1, |p| p.0).max(1);
    let x = |i: usize| l + (width - l - r) * i as f64 / last as f64;
    let y = |v: f64| t + (height - t - b) * (hi - v) / (hi - lo);
    let mut s = format!(
        "<svg class=\"e-d\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" role=\"img\" aria-label=\"E_d per iteration\">"
    );
    let _ = write!(
        s,
        "<line x1=\"{l}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"#444\"/><line x1=\"{l}\" y1=\"{t}\" x2=\"{l}\" y2=\"{}\" stroke=\"#444\"/>",
        height - b,
        width - r,
        height - b,
        height - b
    );
    // Decades on the y axis.
    let mut e = lo as i32;
    while e as f64 <= hi {
        let yy = y(e as f64);
        let _ = write!(
            s,
            "<line x1=\"{}\" y1=\"{yy:.1}\" x2=\"{}\" y2=\"{yy:.1}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{:.1}\" font-size=\"11\" text-anchor=\"end\">1e{e}</text>",
            l,
            width - r,
            l - 4.0,
            yy + 4.0
        );
        e += 1;
    }
    // Integer iteration ticks, at most about eight.
    let step = (last as f64 / 8.0).ceil().max(1.0) as usize;
    for i in (0..=last).step_by(step) {
        let _ = write!(
            s,
            "<text x=\"{:.1}\" y=\"{}\" font-size=\"11\" text-anchor=\"middle\">{i}</text>",
            x(i),
            height - b + 14.0
        );
    }
    let _ = write!(
        s,
        "<text x=\"{:.1}\" y=\"{}\" font-size=\"12\" text-anchor=\"middle\">iteration</text><text x=\"12\" y=\"{:.1}\" font-size=\"12\" transform=\"rotate(-90 12 {:.1})\" text-anchor=\"middle\">E_d (subject unit²)</text>",
        l + (width - l - r) / 2.0,
        height - 4.0,
        t + (height - t - b) / 2.0,
        t + (height - t - b) / 2.0
    );
    let line: Vec<String> = pts
        .iter()
        .map(|&(i, v)| format!("{:.1},{:.1}", x(i), y(v)))
        .collect();
    let _ = write!(
        s,
        "<polyline fill=\"none\" stroke=\"#1f5fa8\" stroke-width=\"1.5\" points=\"{}\"/>",
        line.join(" ")
    );
    for &(i, v) in [pts[0], pts[pts.len() - 1]].iter() {
        let _ = write!(
            s,
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.5\" fill=\"#1f5fa8\"><title>iteration {i}: {:.4e}</title></circle>",
            x(i),
            y(v),
            10f64.powf(v)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// The materials' table: the CT, the recipe's law, and the figures of the map.
pub(crate) fn materials(h: &mut String, m: &crate::materials::MaterialSummary) {
    let rows: Vec<(&str, String)> = vec![
        ("CT", escape(&m.ct)),
        (
            "law",
            format!("{} ({})", escape(&m.law), escape(&m.law_source)),
        ),
        (
            "calibration",
            format!(
                "ρ<sub>QCT</sub> = {} + {} · HU g/cm³",
                num(m.calibration.intercept, 4),
                num(m.calibration.slope, 6)
            ),
        ),
        (
            "integration",
            match m.method {
                Some(crate::materials::IntegrationMethod::V2) => "V2: HU averaged, then E".into(),
                Some(crate::materials::IntegrationMethod::Centroid) => {
                    "the CT at each element's centroid, then E".into()
                }
                _ => "V3: E at every point, then averaged".to_string(),
            },
        ),
        ("elements", m.elements.to_string()),
        ("mean HU (volume-weighted)", num(m.mean_hu, 1)),
        (
            "E min / median / max (MPa)",
            format!(
                "{} / {} / {}",
                num(m.modulus_min, 0),
                num(m.modulus_median, 0),
                num(m.modulus_max, 0)
            ),
        ),
        ("E volume-weighted mean (MPa)", num(m.modulus_mean, 0)),
        (
            "materials (gap in E)",
            format!("{} ({} MPa)", m.materials, num(m.gap, 2)),
        ),
        ("elements at the E floor", m.at_floor.to_string()),
        (
            "elements partly outside the CT",
            m.partly_outside.to_string(),
        ),
        ("elements holding metal", m.metal_elements.to_string()),
        (
            "boundary elements in soft tissue",
            format!("{} %", num(100.0 * m.partial_volume_share, 1)),
        ),
    ];
    h.push_str("<h2>Materials from the CT</h2>\n<table class=\"measures\"><tbody>");
    for (k, v) in rows {
        let _ = write!(h, "<tr><td>{}</td><td>{v}</td></tr>", escape(k));
    }
    h.push_str("</tbody></table>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_e_d_plot_has_integer_ticks_and_a_point_per_iteration() {
        let s = e_d_svg(&[10.0, 1.0, 0.1, 0.05], 400.0, 200.0);
        assert!(s.contains(">0</text>") && s.contains(">3</text>"), "{s}");
        assert!(!s.contains(">0.5<"), "{s}");
        assert_eq!(s.matches("<polyline").count(), 1);
        let pts = s
            .split("points=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        assert_eq!(pts.split(' ').count(), 4);
        assert!(e_d_svg(&[1.0], 400.0, 200.0).contains("fewer than two"));
    }
}
