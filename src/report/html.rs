//! `report.html`: the index of a run, beside `report.json` and the subjects' folders (no
//! network, no external script; the pictures are the PNG files of the run, linked), with the
//! run's parameters, the population's plots (cumulative variance,
//! compactness/generalization/specificity, the modes at ±2σ, `E_d` per iteration, the
//! histogram of scaled Jacobians, the baselines' normal correlations), a link to the model's
//! page (`model.html`: the mean and its mesh along the modes, in 3D) and a sortable table with
//! a row per subject: its measures, its `E_d` against the iterations, a thumbnail, and links
//! to its page (`NAME.html`: its interactive view, measures, worst elements) and its files.
//! The page stays small whatever the number of subjects: a row and a thumbnail of a few
//! kilobytes each.
//!
//! When the page has loaded, a small script checks that every image decoded and records it
//! on `<body>` (`data-images`, `data-broken`), records script errors (`data-errors`) and how
//! far its widest table goes beyond the window (`data-overflow`, pixels): the test opens the
//! page in headless Chromium and reads them back.

use super::{Report, SubjectReport};
use crate::error::Result;
use std::fmt::Write as _;
use std::path::Path;

/// Pictures of the population beside the standard ones (file names in the output folder).
#[derive(Clone, Debug, Default)]
pub struct Pictures {
    /// Compactness, generalization, specificity.
    pub measures: Option<String>,
    /// The modes at ±2σ.
    pub modes: Option<String>,
    /// The model's page, or why it was not written.
    pub model_page: Option<std::result::Result<String, String>>,
}

/// `s` as HTML text or attribute value: markup escaped, and the invisible characters that
/// reorder or hide text (bidirectional overrides: display spoofing) shown as `�`.
pub(crate) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\u{061C}'
            | '\u{200B}'..='\u{200F}'
            | '\u{202A}'..='\u{202E}'
            | '\u{2060}'..='\u{2069}'
            | '\u{FEFF}' => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

/// `<img>` of a PNG file in `dir`, linked (relative to the page); empty when the file is not
/// there.
pub(crate) fn linked_img(dir: &Path, file: &str, alt: &str, class: &str) -> String {
    if dir.join(file).is_file() {
        format!(
            "<img class=\"{class}\" alt=\"{}\" src=\"{}\">",
            escape(alt),
            escape(file)
        )
    } else {
        String::new()
    }
}

/// A small inline SVG line of `E_d` against the iterations (log scale).
fn sparkline(v: &[f64]) -> String {
    let pts: Vec<f64> = v
        .iter()
        .filter(|x| x.is_finite() && **x > 0.0)
        .map(|x| x.ln())
        .collect();
    if pts.len() < 2 {
        return String::new();
    }
    let (lo, hi) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let span = (hi - lo).max(1e-12);
    let (w, h) = (90.0, 30.0);
    let coords: Vec<String> = pts
        .iter()
        .enumerate()
        .map(|(i, &y)| {
            format!(
                "{:.1},{:.1}",
                i as f64 / (pts.len() - 1) as f64 * w,
                h - 2.0 - (y - lo) / span * (h - 4.0)
            )
        })
        .collect();
    format!(
        "<svg class=\"spark\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" role=\"img\" aria-label=\"E_d per iteration\"><polyline fill=\"none\" stroke=\"#1f5fa8\" stroke-width=\"1.5\" points=\"{}\"/></svg>",
        coords.join(" ")
    )
}

pub(crate) fn num(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "–".into()
    }
}

/// Writes `report.html` for `report`, embedding the pictures found in `dir` (the run's output
/// folder).
pub fn write(path: &Path, report: &Report, dir: &Path, pictures: &Pictures) -> Result<()> {
    let mut h = String::with_capacity(1 << 20);
    let title = title(report);
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>{STYLE}</style></head>\n<body>\n<h1>{}</h1>",
        escape(&title),
        escape(&title)
    );
    summary(&mut h, report);
    population(&mut h, report, dir, pictures);
    failures(&mut h, report);
    subjects(&mut h, report, dir);
    let _ = write!(h, "<script>{SCRIPT}</script>\n</body></html>\n");
    crate::formats::write_atomic(path, h.as_bytes())
}

/// The page's title: what the run did, to how many subjects, with which atlas (its file's
/// name; the paths are in the page).
fn title(report: &Report) -> String {
    let n = report.summary.subjects + report.summary.failed;
    let of = |what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    match &report.atlas {
        Some(a) => format!(
            "atlasmesh fit: {} with the atlas {}",
            of("subject"),
            Path::new(&a.file)
                .file_name()
                .map_or_else(|| a.file.clone(), |f| f.to_string_lossy().into_owned())
        ),
        None => match report.folds {
            Some(k) => format!("atlasmesh {k}-fold cross-validation: {}", of("shape")),
            None => format!("atlasmesh leave-one-out: {}", of("shape")),
        },
    }
}

/// The run's facts: data, atlas, dimension, modes, version, the summary table, the mean mesh,
/// the parameters.
fn summary(h: &mut String, report: &Report) {
    let s = &report.summary;
    let _ = writeln!(
        h,
        "<p class=\"meta\">Data: {}{}</p>",
        escape(&report.dataset),
        report.atlas.as_ref().map_or(String::new(), |a| format!(
            " · atlas: {} (CRC-32 {})",
            escape(&a.file),
            escape(&a.checksum_crc32)
        ))
    );
    let _ = writeln!(
        h,
        "<p class=\"meta\">{}D, {} modes (variance explained {}), atlasmesh {}{}</p>",
        report.dimension,
        report.modes,
        report
            .variance_explained
            .last()
            .map_or("–".into(), |v| format!("{:.1} %", 100.0 * v)),
        escape(&report.atlasmesh_version),
        report
            .shard
            .as_ref()
            .map_or(String::new(), |s| format!(", shard {}", escape(s)))
    );
    let _ = writeln!(
        h,
        "<table class=\"summary\"><tr><th>subjects</th><th>succeeded</th><th>meshes valid</th><th>failed</th><th>fit too far</th><th>mesh too far</th><th>mesh quality</th><th>needed repair</th><th>below the repair bound</th><th>morphs stiffened</th><th>fits not converged</th><th>median fit time</th><th>median mesh RMS distance (data units)</th><th>median mesh 95th percentile (data units)</th><th>median RMS distance of the fit (share of the diagonal)</th><th>median normal correlation (−1 to 1)</th></tr>\n<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{} ms</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr></table>",
        s.subjects,
        s.succeeded,
        s.meshes_valid,
        s.failed,
        s.failed_fit,
        s.failed_mesh_distance,
        s.failed_mesh_quality,
        s.repaired,
        s.below_repair_bound,
        s.morph_escalations,
        s.not_converged,
        num(s.median_fit_seconds * 1e3, 1),
        num(s.median_mesh_rms_distance, 3),
        num(s.median_mesh_p95_distance, 3),
        num(s.median_rms_distance_relative, 4),
        num(s.median_normal_correlation, 3)
    );
    if let Some(mm) = &report.mean_mesh {
        let _ = writeln!(
            h,
            "<p>Mean mesh: {} nodes, {} {} elements, min scaled Jacobian {}.</p>",
            mm.nodes,
            mm.elements,
            escape(&mm.element_kind),
            num(mm.scaled_jacobian_min, 3)
        );
    }
    let params = serde_json::to_string_pretty(&report.parameters).unwrap_or_default();
    let _ = writeln!(
        h,
        "<details><summary>Parameters (everything needed to repeat the run{})</summary><pre>{}</pre></details>",
        if report.atlas.is_some() {
            ", with the atlas named above"
        } else {
            ""
        },
        escape(&params)
    );
}

/// The population's figures.
fn population(out: &mut String, report: &Report, dir: &Path, pictures: &Pictures) {
    // (Nothing at all without pictures: a run with `--no-plots`.)
    let mut body = String::new();
    let h = &mut body;
    let mut figs: Vec<(String, &str)> = vec![
        (
            "cumulative_variance.png".into(),
            "Cumulative variance against the number of modes (fig. 5)",
        ),
        (
            "e_d.png".into(),
            "E_d per iteration, every subject (fig. 11/19)",
        ),
        (
            "scaled_jacobians.png".into(),
            "Scaled Jacobians of every element of every subject",
        ),
    ];
    if let Some(m) = &pictures.measures {
        figs.insert(
            1,
            (
                m.clone(),
                "Compactness, generalization and specificity of the model",
            ),
        );
    }
    if let Some(m) = &pictures.modes {
        figs.insert(
            1,
            (
                m.clone(),
                "The mean and ±2σ along the first modes (figs. 4, 15)",
            ),
        );
    }
    if report
        .subjects
        .iter()
        .any(|s| s.normal_correlation_icp.is_some())
    {
        figs.push((
            "baselines.png".into(),
            "Normal correlation: SSM fit against the FFD and ICP baselines (fig. 12/20)",
        ));
    }
    if let Some(page) = &pictures.model_page {
        match page {
            Ok(f) => {
                let _ = writeln!(
                    h,
                    "<p><a href=\"{}\">The model in 3D</a>: the mean shape and its FE mesh along each mode, with a slider.</p>",
                    escape(f)
                );
            }
            Err(why) => {
                let _ = writeln!(
                    h,
                    "<p class=\"hint\">The model's page was not written: {}</p>",
                    escape(why)
                );
            }
        }
    }
    for (file, caption) in &figs {
        let i = linked_img(dir, file, caption, "fig");
        if !i.is_empty() {
            let _ = writeln!(
                h,
                "<figure>{i}<figcaption>{}</figcaption></figure>",
                escape(caption)
            );
        }
    }
    if !body.is_empty() {
        out.push_str("<h2>Population</h2>\n<div class=\"figs\">\n");
        out.push_str(&body);
        out.push_str("</div>\n");
    }
}

/// The table of the subjects that failed, and why.
fn failures(h: &mut String, report: &Report) {
    if !report.failed.is_empty() {
        h.push_str("<h2>Failed subjects</h2>\n<table><tr><th>subject</th><th>input</th><th>reason</th></tr>\n");
        for f in &report.failed {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
                escape(&f.name),
                escape(&f.input),
                escape(&f.error)
            );
        }
        h.push_str("</table>\n");
    }
}

/// The table of the subjects, a row each, sortable.
fn subjects(h: &mut String, report: &Report, dir: &Path) {
    let baselines = report
        .subjects
        .iter()
        .any(|s| s.normal_correlation_icp.is_some());
    let columns = Columns {
        baselines,
        cut: report.subjects.iter().any(|s| s.atlas_cut.is_some()),
        pictures: report
            .subjects
            .iter()
            .any(|s| s.files.iter().any(|f| f.ends_with("_thumb.png"))),
    };
    h.push_str("<h2>Subjects</h2>\n<p class=\"hint\">Click a column's title to sort.</p>\n<div class=\"wide\"><table id=\"subjects\" class=\"sortable\"><thead><tr>");
    let mut cols = vec!["subject"];
    if columns.pictures {
        cols.push("picture");
    }
    cols.extend([
        "success",
        "checks failed, warnings",
        "mesh RMS distance (data units)",
        "mesh 95th percentile (data units)",
        "iterations",
        "fit (ms)",
        "RMS distance of the fit (share of the diagonal)",
        "normal correlation",
    ]);
    if baselines {
        cols.extend(["FFD baseline", "ICP baseline"]);
    }
    if columns.cut {
        cols.push("share of the atlas covered, of the subject beyond the atlas's cut");
    }
    cols.extend([
        "min scaled Jacobian",
        "before repair",
        "inverted",
        "E_d per iteration",
    ]);
    for c in &cols {
        let _ = write!(h, "<th>{}</th>", escape(c));
    }
    h.push_str("</tr></thead><tbody>\n");
    for s in &report.subjects {
        subject_row(h, s, dir, columns);
    }
    h.push_str("</tbody></table></div>\n");
}

/// The optional columns of the subjects' table: the baselines', the atlas's cut, the
/// thumbnails (absent without pictures).
#[derive(Clone, Copy)]
struct Columns {
    baselines: bool,
    cut: bool,
    pictures: bool,
}

/// A subject's row, with the optional `columns`.
fn subject_row(h: &mut String, s: &SubjectReport, dir: &Path, columns: Columns) {
    let page = s.files.iter().find(|f| f.ends_with(".html"));
    let name = match page {
        Some(p) => format!(
            "<a href=\"{}\" title=\"its page: view, measures, worst elements\">{}</a>",
            escape(p),
            escape(&s.name)
        ),
        None => escape(&s.name),
    };
    let _ = write!(
        h,
        "<tr><td data-v=\"{}\">{name}{}</td>{}<td data-v=\"{}\">{}</td><td class=\"notes\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>",
        escape(&s.name),
        file_links(s),
        if columns.pictures {
            thumbnail_cell(s, dir, page)
        } else {
            String::new()
        },
        u8::from(s.success),
        if s.success { "yes" } else { "<b>no</b>" },
        escape(
            &s.failed_checks
                .iter()
                .chain(&s.warnings)
                .cloned()
                .collect::<Vec<_>>()
                .join("; ")
        ),
        num(s.mesh_rms_distance, 3),
        num(s.mesh_p95_distance, 3),
        s.iterations,
        num(s.fit_seconds * 1e3, 1),
        num(s.rms_distance_relative, 4),
        num(s.normal_correlation, 3)
    );
    if columns.baselines {
        let _ = write!(
            h,
            "<td>{}</td><td>{}</td>",
            num(s.normal_correlation_ffd.unwrap_or(f64::NAN), 3),
            num(s.normal_correlation_icp.unwrap_or(f64::NAN), 3)
        );
    }
    if columns.cut {
        // Where the subject's mesh ends: how much of the atlas it covers (below 100 % when
        // the field of view cut it short of the atlas's cut), how much of it lies beyond.
        match &s.atlas_cut {
            Some(c) => {
                let _ = write!(
                    h,
                    "<td data-v=\"{}\">covers {} %, {} % beyond</td>",
                    c.atlas_covered_share,
                    num(100.0 * c.atlas_covered_share, 1),
                    num(100.0 * c.beyond_share, 1)
                );
            }
            None => h.push_str("<td></td>"),
        }
    }
    let _ = write!(
        h,
        "<td>{}</td><td>{}</td><td>{}</td><td>{}</td>",
        num(s.scaled_jacobian_min, 3),
        num(s.scaled_jacobian_min_before_repair, 3),
        s.inverted_elements,
        sparkline(&s.e_d_history)
    );
    h.push_str("</tr>\n");
}

/// A subject's files, linked (relative to the report's folder) under its name, each shown by
/// what follows the subject's name (`mesh.vtu`, `fit.vtp`; its page as `page`), named whole
/// in the title: the table then fits a 1400-pixel window.
fn file_links(s: &SubjectReport) -> String {
    fn whole(f: &str) -> &str {
        f.rsplit('/').next().unwrap_or(f)
    }
    // (The files' common start: the page's name, `NAME.html`, or else the subject's name.)
    let base = s
        .files
        .iter()
        .find(|f| f.ends_with(".html"))
        .map_or(s.name.as_str(), |f| whole(f).trim_end_matches(".html"));
    let mut h = String::from("<div class=\"files\">");
    for f in s.files.iter().filter(|f| !f.ends_with(".png")) {
        let whole = whole(f);
        let short = if whole.ends_with(".html") {
            "page"
        } else {
            whole
                .strip_prefix(base)
                .and_then(|r| r.strip_prefix('_'))
                .filter(|r| !r.is_empty())
                .unwrap_or(whole)
        };
        let _ = write!(
            h,
            "<a href=\"{}\" title=\"{}\">{}</a> ",
            escape(f),
            escape(whole),
            escape(short)
        );
    }
    h.push_str("</div>");
    h
}

/// The thumbnail cell of a subject's row: its picture, linked to its page.
fn thumbnail_cell(s: &SubjectReport, dir: &Path, page: Option<&String>) -> String {
    let mut h = String::from("<td class=\"pics\">");
    if let Some(f) = s.files.iter().find(|f| f.ends_with("_thumb.png")) {
        let what = if s.files.iter().any(|f| f.ends_with("_quality.png")) {
            "morphed mesh, scaled Jacobian (red 0, yellow 0.5, green 1)"
        } else {
            "mean (red), subject (blue), locus (green); morphed mesh by scaled Jacobian"
        };
        let i = linked_img(dir, f, &format!("{}: {what}", s.name), "thumb");
        if !i.is_empty() {
            match page {
                Some(p) => {
                    let _ = write!(
                        h,
                        "<a href=\"{}\" title=\"{}\">{i}</a>",
                        escape(p),
                        escape(what)
                    );
                }
                None => h.push_str(&i),
            }
        }
    }
    h.push_str("</td>");
    h
}

pub(crate) const STYLE: &str = "body{font-family:system-ui,sans-serif;margin:1.5em;color:#222}\
h1{font-size:1.4em}h2{font-size:1.15em;margin-top:1.6em}\
table{border-collapse:collapse;font-size:0.9em}th,td{border:1px solid #ccc;padding:3px 6px;text-align:right}\
th{background:#f0f0f0;cursor:pointer}td:first-child{text-align:left}\
.figs{display:flex;flex-wrap:wrap;gap:12px}figure{margin:0}figcaption{font-size:0.85em;color:#555;max-width:640px}\
img.fig{max-width:640px;border:1px solid #ddd}img.thumb{max-height:120px;max-width:220px;margin:1px;border:1px solid #ddd}\
td.pics{white-space:nowrap;text-align:left}.wide{overflow-x:auto;max-width:100%}\
td.notes{text-align:left;min-width:12em;max-width:28em}td.notes:empty{min-width:0}div.files{font-size:0.85em;max-width:14em}.meta,.hint{color:#555}pre{font-size:0.8em}\
.verdict.ok{color:#1a7f37}.verdict.bad{color:#b42318;font-weight:bold}tr[data-focus]{cursor:pointer}\
tr[data-focus]:hover{background:#f6f0ff}table.measures td{text-align:left}";

pub(crate) const SCRIPT: &str = r#"
(function () {
  var errors = [];
  window.addEventListener('error', function (e) {
    errors.push(String(e.message || e));
    document.body.setAttribute('data-errors', errors.join(' | '));
  });
  function key(td) {
    var v = td.getAttribute('data-v');
    if (v === null) v = td.textContent.trim();
    var x = parseFloat(v);
    return isNaN(x) ? v.toLowerCase() : x;
  }
  document.querySelectorAll('table.sortable th').forEach(function (th, col) {
    th.addEventListener('click', function () {
      var body = th.closest('table').tBodies[0];
      var rows = Array.prototype.slice.call(body.rows);
      var up = th.getAttribute('data-dir') !== 'up';
      th.setAttribute('data-dir', up ? 'up' : 'down');
      rows.sort(function (a, b) {
        var x = key(a.cells[col]), y = key(b.cells[col]);
        if (x === y) return 0;
        return (x < y ? -1 : 1) * (up ? 1 : -1);
      });
      rows.forEach(function (r) { body.appendChild(r); });
    });
  });
  window.addEventListener('load', function () {
    var imgs = Array.prototype.slice.call(document.images);
    var broken = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); });
    document.body.setAttribute('data-images', String(imgs.length));
    document.body.setAttribute('data-broken', String(broken.length));
    document.body.setAttribute('data-errors', errors.join(' | '));
    var over = 0;
    document.querySelectorAll('.wide').forEach(function (w) {
      over = Math.max(over, w.scrollWidth - w.clientWidth);
    });
    document.body.setAttribute('data-overflow', String(over));
  });
})();
"#;

/// Writes `instances.html` for the instances of `report` (`atlasmesh instance` or `sample`),
/// with the thumbnails of their pictures found in `dir` (linked to the pictures): the summary, the weights of the first two modes
/// against each other (a sampled population's spread), and a sortable table with a row per
/// instance (its weights, its mesh's quality and distance to its surface, its files).
pub fn write_instances(path: &Path, report: &super::InstancesReport, dir: &Path) -> Result<()> {
    let mut h = String::with_capacity(1 << 20);
    let title = "atlasmesh instances of the model";
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{title}</title>\n<style>{STYLE}</style></head>\n<body>\n<h1>{title}</h1>"
    );
    let s = &report.summary;
    let unit = if report.data_unit {
        "the data's unit"
    } else {
        "the atlas's reference frame (an atlas of format 2)"
    };
    let _ = writeln!(
        h,
        "<p class=\"meta\">Atlas {} ({}D, {} modes); shapes and meshes in {unit}; atlasmesh {}.{}</p>",
        escape(&report.atlas),
        report.dimension,
        report.modes,
        escape(&report.atlasmesh_version),
        report.sampling.as_ref().map_or(String::new(), |p| format!(
            " Sampled: {} weights vectors from the prior N(0, Λ), seed {}{}.",
            p.n,
            p.seed,
            p.max_sd
                .map_or(String::new(), |k| format!(", each weight within ±{k} sd"))
        ))
    );
    let _ = writeln!(
        h,
        "<table><tbody><tr><td>instances written</td><td>{}</td></tr><tr><td>failed</td><td>{}</td></tr><tr><td>skipped (complete)</td><td>{}</td></tr><tr><td>with elements below the repair bound</td><td>{}</td></tr><tr><td>smallest scaled Jacobian</td><td>{}</td></tr><tr><td>largest boundary RMS distance / element size</td><td>{}</td></tr></tbody></table>",
        s.written,
        s.failed,
        s.resumed,
        s.below_repair_bound,
        num(s.scaled_jacobian_min, 3),
        num(s.mesh_rms_distance_per_element_max, 4)
    );
    if report.modes >= 2 && report.instances.len() > 1 {
        h.push_str("<h2>Weights of modes 1 and 2</h2>\n");
        h.push_str(&weights_scatter(&report.instances));
    }
    if !report.failed.is_empty() {
        h.push_str("<h2>Failed</h2>\n<table><thead><tr><th>instance</th><th>reason</th></tr></thead><tbody>\n");
        for f in &report.failed {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}</td></tr>",
                escape(&f.name),
                escape(&f.error)
            );
        }
        h.push_str("</tbody></table>\n");
    }
    instances_table(&mut h, report, dir);
    let _ = write!(h, "<script>{SCRIPT}</script>\n</body></html>\n");
    crate::formats::write_atomic(path, h.as_bytes())
}

/// The sortable table of `instances.html`: a row per instance (its weights of the first five
/// modes, its mesh's quality and distance to its surface, its files and thumbnail).
fn instances_table(h: &mut String, report: &super::InstancesReport, dir: &Path) {
    let shown = report.modes.min(5);
    h.push_str("<h2>Instances</h2>\n<table class=\"sortable\"><thead><tr><th>instance</th><th>Mahalanobis</th>");
    for k in 1..=shown {
        let _ = write!(h, "<th>mode {k} (sd)</th>");
    }
    h.push_str("<th>elements</th><th>SJ min</th><th>SJ min before repair</th><th>below repair bound</th><th>boundary RMS</th><th>RMS / element</th><th>boundary p95</th><th>element size</th><th>files</th><th>picture</th></tr></thead><tbody>\n");
    for r in &report.instances {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td>",
            escape(&r.name),
            num(r.mahalanobis, 2)
        );
        for m in 0..shown {
            let _ = write!(
                h,
                "<td>{}</td>",
                num(r.sd.get(m).copied().unwrap_or(0.0), 2)
            );
        }
        let _ = write!(
            h,
            "<td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>",
            r.elements,
            num(r.scaled_jacobian_min, 3),
            num(r.scaled_jacobian_min_before_repair, 3),
            r.elements_below_repair_bound,
            num(r.mesh_rms_distance, 4),
            num(r.mesh_rms_distance / r.element_size, 4),
            num(r.mesh_p95_distance, 4),
            num(r.element_size, 3)
        );
        for f in r.files.iter().filter(|f| !f.ends_with(".png")) {
            let short = f.rsplit('/').next().unwrap_or(f);
            let _ = write!(h, "<a href=\"{}\">{}</a> ", escape(f), escape(short));
        }
        h.push_str("</td><td class=\"pics\">");
        let full = r
            .files
            .iter()
            .find(|f| f.ends_with(".png") && !f.ends_with("_thumb.png"));
        if let (Some(t), Some(full)) = (r.files.iter().find(|f| f.ends_with("_thumb.png")), full) {
            let i = linked_img(dir, t, &format!("{}: its mesh", r.name), "thumb");
            let _ = write!(h, "<a href=\"{}\">{i}</a>", escape(full));
        }
        h.push_str("</td></tr>\n");
    }
    h.push_str("</tbody></table>\n");
}

/// An inline SVG of the instances' weights of mode 1 (x) against mode 2 (y), in standard
/// deviations, with the 1, 2 and 3 sd circles; each dot titled with its instance.
fn weights_scatter(instances: &[super::InstanceReport]) -> String {
    let (size, pad) = (320.0, 20.0);
    let reach = instances
        .iter()
        .flat_map(|r| r.sd.iter().take(2))
        .filter(|v| v.is_finite())
        .fold(3.0_f64, |a, v| a.max(v.abs()))
        .ceil();
    let scale = (size / 2.0 - pad) / reach;
    let c = size / 2.0;
    let mut svg = format!(
        "<svg width=\"{size}\" height=\"{size}\" viewBox=\"0 0 {size} {size}\" role=\"img\" aria-label=\"weights of modes 1 and 2 in sd\">"
    );
    for k in 1..=3 {
        let _ = write!(
            svg,
            "<circle cx=\"{c}\" cy=\"{c}\" r=\"{:.1}\" fill=\"none\" stroke=\"#bbb\"/><text x=\"{:.1}\" y=\"{:.1}\" font-size=\"10\" fill=\"#777\">{k}σ</text>",
            k as f64 * scale,
            c + k as f64 * scale * 0.71 + 2.0,
            c - k as f64 * scale * 0.71 - 2.0
        );
    }
    let _ = write!(
        svg,
        "<line x1=\"{pad}\" y1=\"{c}\" x2=\"{}\" y2=\"{c}\" stroke=\"#888\"/><line x1=\"{c}\" y1=\"{pad}\" x2=\"{c}\" y2=\"{}\" stroke=\"#888\"/><text x=\"{}\" y=\"{}\" font-size=\"11\">mode 1</text><text x=\"{}\" y=\"{}\" font-size=\"11\">mode 2</text>",
        size - pad,
        size - pad,
        size - pad - 40.0,
        c - 4.0,
        c + 4.0,
        pad + 8.0
    );
    for r in instances {
        let (x, y) = (
            r.sd.first().copied().unwrap_or(0.0),
            r.sd.get(1).copied().unwrap_or(0.0),
        );
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        let _ = write!(
            svg,
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"3\" fill=\"#1f5fa8\"><title>{}: {x:.2}, {y:.2}</title></circle>",
            c + x * scale,
            c - y * scale,
            escape(&r.name)
        );
    }
    svg.push_str("</svg>\n");
    svg
}
