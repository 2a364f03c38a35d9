//! The page of `atlasmesh materials` (`report.html` beside `report.json`): what the CT gave
//! the mesh (the law, the calibration, the figures of the map, its checks), the recipe's parts
//! of constant material, the load case's sets and, when the model was solved, the stiffness,
//! the reaction forces, the solver's time and memory, and the picture of the displacement;
//! the files, linked. The page checks its images once loaded, as `report.html` of a run does.

use super::MaterialsReport;
use super::html::{SCRIPT, STYLE, escape, linked_img, num};
use crate::error::Result;
use std::fmt::Write as _;
use std::path::Path;

/// Writes the page of `report` to `path`; its pictures and files are those of `report` in
/// `dir` (the page's folder).
///
/// # Errors
/// [`crate::Error::Io`] when the page cannot be written.
pub fn write_materials_page(path: &Path, report: &MaterialsReport, dir: &Path) -> Result<()> {
    crate::formats::write_atomic(path, materials_page(report, dir).as_bytes())
}

/// The page's HTML (see the module).
fn materials_page(r: &MaterialsReport, dir: &Path) -> String {
    let mut h = String::with_capacity(1 << 14);
    let name = Path::new(&r.mesh)
        .file_name()
        .map_or_else(|| r.mesh.clone(), |n| n.to_string_lossy().into_owned());
    let title = format!("atlasmesh: materials of {name}");
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\n\
         <style>{STYLE}</style></head>\n<body>\n<h1>{t}</h1>\n<p class=\"meta\">atlasmesh {} · \
         mesh {} ({} elements, {})</p>",
        escape(&r.version),
        escape(&r.mesh),
        r.materials.elements,
        escape(&r.element_kind),
        t = escape(&title),
    );
    if let Some(s) = &r.solve {
        let _ = writeln!(
            h,
            "<p class=\"verdict ok\">Stiffness <b>{} N/mm</b>: a reaction of {} N on {} along {} \
             for its displacement of {} mm (CalculiX, {} s).</p>",
            num(s.stiffness_n_per_mm, 0),
            num(s.reaction_n, 1),
            escape(&s.loaded_set),
            escape(&s.axis),
            num(s.displacement_mm, 4),
            num(s.seconds, 1)
        );
    }
    let warnings = &r.materials.warnings;
    if !warnings.is_empty() {
        h.push_str("<ul class=\"warnings\">");
        for w in warnings {
            let _ = write!(h, "<li>{}</li>", escape(w));
        }
        h.push_str("</ul>\n");
    }
    for f in r.files.iter().filter(|f| f.ends_with(".png")) {
        h.push_str(&linked_img(dir, f, f, "fig"));
    }
    super::subject_page::materials(&mut h, &r.materials);
    parts(&mut h, r);
    solve(&mut h, r);
    h.push_str("<h2>Files</h2>\n<ul>");
    for f in std::iter::once(&"report.json".to_string()).chain(&r.files) {
        let _ = write!(h, "<li><a href=\"{0}\">{0}</a></li>", escape(f));
    }
    let _ = write!(h, "</ul>\n<script>{SCRIPT}</script>\n</body></html>\n");
    h
}

/// The recipe's parts (name, elements, volume in mm³, E in MPa, ν) and the load case's sets
/// (node counts).
fn parts(h: &mut String, r: &MaterialsReport) {
    if !r.materials.parts.is_empty() {
        h.push_str(
            "<h2>Parts of constant material</h2>\n<table class=\"measures\"><thead><tr>\
             <th>part</th><th>elements</th><th>volume (mm³)</th><th>E (MPa)</th><th>ν</th>\
             </tr></thead><tbody>",
        );
        for p in &r.materials.parts {
            let _ = write!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                escape(&p.name),
                p.elements,
                num(p.volume, 0),
                num(p.modulus, 0),
                num(p.poisson, 3)
            );
        }
        h.push_str("</tbody></table>\n");
    }
    if !r.load_sets.is_empty() {
        h.push_str(
            "<h2>Load case</h2>\n<table class=\"measures\"><thead><tr><th>node set</th>\
             <th>nodes</th></tr></thead><tbody>",
        );
        for (set, n) in &r.load_sets {
            let _ = write!(h, "<tr><td>{}</td><td>{n}</td></tr>", escape(set));
        }
        h.push_str("</tbody></table>\n");
    }
}

/// The solve: the solver's run and every set's reaction force (N, x y z).
fn solve(h: &mut String, r: &MaterialsReport) {
    let Some(s) = &r.solve else {
        return;
    };
    let rows = [
        ("solver", escape(&s.solver)),
        ("deck", escape(&s.deck)),
        ("wall time (s)", num(s.seconds, 1)),
        ("peak memory (MB)", num(s.peak_memory_mb, 0)),
        (
            "largest displacement (mm)",
            s.largest_displacement_mm.map_or("—".into(), |u| num(u, 4)),
        ),
        ("tied nodes left free", s.untied_nodes.to_string()),
    ];
    h.push_str("<h2>Solve</h2>\n<table class=\"measures\"><tbody>");
    for (k, v) in rows {
        let _ = write!(h, "<tr><td>{k}</td><td>{v}</td></tr>");
    }
    h.push_str(
        "</tbody></table>\n<table class=\"measures\"><thead><tr><th>set</th><th>reaction x (N)\
         </th><th>reaction y (N)</th><th>reaction z (N)</th></tr></thead><tbody>",
    );
    for (set, f) in &s.reactions {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(set),
            num(f[0], 2),
            num(f[1], 2),
            num(f[2], 2)
        );
    }
    h.push_str("</tbody></table>\n");
}
