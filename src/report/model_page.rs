//! The model's page, `model.html`: the mean shape and its FE mesh moved along the modes by a
//! slider, with the modes' variances.

use super::html::{STYLE, escape, num};
use super::viewer::{Scene, VIEWER_SCRIPT, VIEWER_STYLE, viewer_html};
use crate::error::Result;
use std::fmt::Write as _;
use std::path::Path;

/// What the model page shows.
pub struct ModelPage<'a> {
    /// 2 or 3.
    pub dimension: usize,
    /// The mean, its mesh and the modes' displacements.
    pub scene: &'a Scene,
    /// The modes' variances `lambda_k` (the reference frame's unit squared).
    pub variances: &'a [f64],
    /// The cumulative variance share of the modes.
    pub cumulative: &'a [f64],
    /// The data's units per reference-frame unit (the atlas's data frame scale `s`; `None`
    /// for an atlas that does not know it): the variances in the data's unit squared are
    /// `lambda_k s²`, as Python's `Atlas.variances` gives them.
    pub data_per_reference: Option<f64>,
    /// The model's points `N` (a mode is a vector of their `N·D` coordinates).
    pub points: usize,
    /// Nodes of the mean mesh.
    pub nodes: usize,
    /// Elements of the mean mesh.
    pub elements: usize,
    /// Their kind's name.
    pub kind: &'a str,
    /// Pictures beside the page to show under the view (file names).
    pub pictures: &'a [&'a str],
}

/// Writes the model page `page` to `path`.
pub fn write_model_page(path: &Path, page: &ModelPage) -> Result<()> {
    let mut h = String::with_capacity(1 << 16);
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>atlasmesh: the model</title>\n<style>{STYLE}{VIEWER_STYLE}</style></head>\n<body>\n<p class=\"meta\"><a href=\"report.html\">← the run's report</a></p>\n<h1>The model: its mean and modes</h1>\n<p class=\"meta\">{}D; mean mesh of {} nodes and {} {} elements, in the data's frame and unit. Choose a mode and move the slider: the mean shape moves along it exactly (eq. 4), the mesh as the morph (eq. 9) carries it.</p>",
        page.dimension,
        page.nodes,
        page.elements,
        escape(page.kind)
    );
    h.push_str(&viewer_html(page.scene, "scene", 760, 520));
    h.push_str("<h2>Modes</h2>\n");
    if let Some(s) = page.data_per_reference {
        let _ = write!(
            h,
            "<p class=\"meta\">Each mode's variance twice: λ in the model's reference frame \
             (the mean's largest extent 1, the frame of the fit's parameters), and in the data's \
             unit squared, λ s² with s = {} data units per reference unit (Python's \
             <code>Atlas.variances</code>). A mode is one vector of every point's coordinates: \
             its standard deviation, the square root, is the length of a displacement of the {} \
             points together (the root of the sum of their squares); one point's root mean \
             square is √(λ s² / {}).</p>",
            num(s, 6),
            page.points,
            page.points
        );
    }
    h.push_str("<table class=\"measures\"><thead><tr><th>mode</th><th>variance λ (reference frame)</th><th>variance (the data's unit²)</th><th>cumulative share</th></tr></thead><tbody>");
    for (k, v) in page.variances.iter().enumerate() {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{} %</td></tr>",
            k + 1,
            num(*v, 6),
            page.data_per_reference
                .map_or_else(|| "—".to_string(), |s| num(v * s * s, 6)),
            num(
                100.0 * page.cumulative.get(k).copied().unwrap_or(f64::NAN),
                2
            )
        );
    }
    h.push_str("</tbody></table>\n<div class=\"figs\">");
    for f in page.pictures {
        let _ = write!(
            h,
            "<figure><img class=\"fig\" src=\"{}\" alt=\"{}\"></figure>",
            escape(f),
            escape(f)
        );
    }
    let _ = write!(
        h,
        "</div>\n<script>{}</script>\n<script>{VIEWER_SCRIPT}</script>\n</body></html>\n",
        super::html::SCRIPT
    );
    crate::formats::write_atomic(path, h.as_bytes())
}
