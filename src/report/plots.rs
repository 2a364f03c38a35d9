//! PNG plots (plotters): cumulative variance (fig. 5), `E_d` per iteration (fig. 11), the
//! shape-model measures, the modes (fig. 4), and per subject the mean, the subject, the fit's
//! locus and the morphed mesh coloured by scaled Jacobian (fig. 9).

use super::{SubjectReport, render};
use crate::error::{Error, Result};
use crate::geometry::{Point, bounding_box};
use crate::mesh::FeMesh;
use crate::mesh::quality::mesh_quality;
use plotters::prelude::*;
use std::path::Path;

/// An RGB picture that plotters draws into (no image codec: [`Canvas::save`] encodes it).
struct Canvas {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Canvas {
    /// A white picture of `width` × `height` pixels.
    fn new(width: u32, height: u32) -> Self {
        Canvas {
            width,
            height,
            rgb: vec![255; width as usize * height as usize * 3],
        }
    }

    /// Draws on the whole picture with `draw`, then writes it as PNG to `path` (a temporary
    /// name, then a rename).
    fn draw(
        mut self,
        path: &Path,
        draw: impl FnOnce(DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<()>,
    ) -> Result<()> {
        {
            let root = BitMapBackend::with_buffer(&mut self.rgb, (self.width, self.height))
                .into_drawing_area();
            draw(root.clone())?;
            root.present().map_err(perr(path))?;
        }
        let img = render::Image {
            width: self.width as usize,
            height: self.height as usize,
            rgb: self.rgb,
        };
        crate::formats::write_atomic(path, &img.png()?)
    }
}

/// A chart's frame on `area`: the margins, the label areas (`y_label` pixels for the y
/// axis's labels) and the caption, or bare axes where no font is available (`text`).
fn chart_frame<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    y_label: u32,
    text: bool,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(area);
    b.margin(12)
        .x_label_area_size(if text { 36 } else { 5 })
        .y_label_area_size(if text { y_label } else { 5 });
    if text {
        b.caption(caption, ("sans-serif", 20));
    }
    b
}

fn perr<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::io(path, std::io::Error::other(format!("plot: {e}")))
}

/// A tick label of a count axis (modes, iterations): the integer at an integer position,
/// nothing between (no "2.5 modes").
pub(crate) fn integer_label(x: &f64) -> String {
    if (x - x.round()).abs() < 1e-9 {
        format!("{}", x.round() as i64)
    } else {
        String::new()
    }
}

/// Plots the cumulative variance share against the number of modes (fig. 5).
pub fn plot_cumulative_variance(path: &Path, cumulative: &[f64], kept: usize) -> Result<()> {
    let text = super::render::font_available();
    Canvas::new(640, 420).draw(path, |root| {
        root.fill(&WHITE).map_err(perr(path))?;
        let n = cumulative.len().max(1);
        let lo = cumulative.first().copied().unwrap_or(0.0).min(0.9) - 0.02;
        let mut chart = chart_frame(&root, "Cumulative variance", 52, text)
            .build_cartesian_2d(0.5f64..n as f64 + 0.5, lo..1.005f64)
            .map_err(perr(path))?;
        if text {
            chart
                .configure_mesh()
                .x_desc("number of modes")
                .y_desc("share of variance")
                .x_label_formatter(&integer_label)
                .draw()
                .map_err(perr(path))?;
        }
        let pts: Vec<(f64, f64)> = cumulative
            .iter()
            .enumerate()
            .map(|(i, v)| ((i + 1) as f64, *v))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), BLUE.stroke_width(2)))
            .map_err(perr(path))?;
        chart
            .draw_series(pts.iter().enumerate().map(|(i, p)| {
                Circle::new(
                    *p,
                    4,
                    if i < kept {
                        RED.filled()
                    } else {
                        BLUE.filled()
                    },
                )
            }))
            .map_err(perr(path))?;
        Ok(())
    })
}

/// Plots compactness, generalization and specificity against the number of modes, side by
/// side, each with its standard error as a band (Styner et al. 2003, fig. 2).
pub fn plot_shape_model_measures(
    path: &Path,
    m: &crate::eval::ShapeModelMeasures,
    units: &str,
) -> Result<()> {
    let text = super::render::font_available();
    let units = if units.is_empty() {
        "the shapes' unit"
    } else {
        units
    };
    Canvas::new(1200, 400).draw(path, |root| {
        root.fill(&WHITE).map_err(perr(path))?;
        let panels = root.split_evenly((1, 3));
        let series = [
            (
                "Compactness",
                "share of variance".to_string(),
                &m.compactness,
                &m.compactness_sd,
            ),
            (
                "Generalization",
                format!("mean distance ({units})"),
                &m.generalization,
                &m.generalization_sd,
            ),
            (
                "Specificity",
                format!("mean distance ({units})"),
                &m.specificity,
                &m.specificity_sd,
            ),
        ];
        let n = m.modes.len().max(1) as f64;
        for (area, (title, ylabel, v, sd)) in panels.iter().zip(series) {
            let lo = v
                .iter()
                .zip(sd.iter())
                .map(|(a, b)| a - b)
                .fold(f64::INFINITY, f64::min);
            let hi = v
                .iter()
                .zip(sd.iter())
                .map(|(a, b)| a + b)
                .fold(f64::NEG_INFINITY, f64::max);
            let (lo, hi) = if lo.is_finite() && hi > lo {
                let pad = 0.05 * (hi - lo);
                (lo - pad, hi + pad)
            } else {
                (0.0, 1.0)
            };
            let mut chart = chart_frame(area, title, 64, text)
                .build_cartesian_2d(0.5f64..n + 0.5, lo..hi)
                .map_err(perr(path))?;
            if text {
                chart
                    .configure_mesh()
                    .x_desc("number of modes")
                    .y_desc(ylabel.as_str())
                    .x_label_formatter(&integer_label)
                    .draw()
                    .map_err(perr(path))?;
            }
            let band: Vec<(f64, f64)> = m
                .modes
                .iter()
                .zip(v.iter().zip(sd.iter()))
                .map(|(k, (a, e))| (*k as f64, a + e))
                .chain(
                    m.modes
                        .iter()
                        .zip(v.iter().zip(sd.iter()))
                        .rev()
                        .map(|(k, (a, e))| (*k as f64, a - e)),
                )
                .collect();
            chart
                .draw_series(std::iter::once(Polygon::new(band, BLUE.mix(0.2).filled())))
                .map_err(perr(path))?;
            chart
                .draw_series(LineSeries::new(
                    m.modes.iter().zip(v.iter()).map(|(k, a)| (*k as f64, *a)),
                    BLUE.stroke_width(2),
                ))
                .map_err(perr(path))?;
        }
        Ok(())
    })
}

/// Plots `E_d` against the iteration for every subject (fig. 11), log scale.
pub fn plot_e_d(path: &Path, histories: &[(String, Vec<f64>)]) -> Result<()> {
    let text = super::render::font_available();
    Canvas::new(720, 460).draw(path, |root| {
        root.fill(&WHITE).map_err(perr(path))?;
        let maxit = histories
            .iter()
            .map(|h| h.1.len())
            .max()
            .unwrap_or(1)
            .max(2);
        let vals: Vec<f64> = histories
            .iter()
            .flat_map(|h| h.1.iter().copied())
            .filter(|v| *v > 0.0 && v.is_finite())
            .collect();
        // No history (no subject fitted): a fixed decade, not an infinite axis.
        let (lo, hi) = if vals.is_empty() {
            (1.0, 10.0)
        } else {
            let lo = vals
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min)
                .max(1e-300);
            (lo, vals.iter().copied().fold(0.0, f64::max).max(lo * 10.0))
        };
        let mut chart = chart_frame(&root, "E_d per iteration", 64, text)
            .build_cartesian_2d(0f64..maxit as f64, (lo..hi).log_scale())
            .map_err(perr(path))?;
        if text {
            chart
                .configure_mesh()
                .x_desc("iteration")
                .y_desc("E_d")
                .x_label_formatter(&integer_label)
                .draw()
                .map_err(perr(path))?;
        }
        // The subjects that ended highest are drawn in colour and named; the others grey.
        let named = highest_last(histories, E_D_NAMED);
        let points = |h: &[f64]| -> Vec<(f64, f64)> {
            h.iter()
                .enumerate()
                .filter(|(_, v)| **v > 0.0 && v.is_finite())
                .map(|(i, v)| (i as f64, *v))
                .collect()
        };
        for (k, (_, h)) in histories.iter().enumerate() {
            if !named.contains(&k) {
                chart
                    .draw_series(LineSeries::new(points(h), BLACK.mix(0.25).stroke_width(1)))
                    .map_err(perr(path))?;
            }
        }
        for (rank, &k) in named.iter().enumerate() {
            let color = Palette99::pick(rank).to_rgba();
            chart
                .draw_series(LineSeries::new(
                    points(&histories[k].1),
                    color.stroke_width(2),
                ))
                .map_err(perr(path))?
                .label(histories[k].0.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
        }
        if text && !named.is_empty() {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK.mix(0.4))
                .label_font(("sans-serif", 12))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(perr(path))?;
        }
        Ok(())
    })
}

/// Subjects named in the `E_d` plot: those whose last `E_d` is highest.
pub const E_D_NAMED: usize = 6;

/// The indices of the (at most) `k` histories whose last finite value is highest, highest
/// first.
pub(crate) fn highest_last(histories: &[(String, Vec<f64>)], k: usize) -> Vec<usize> {
    let mut last: Vec<(usize, f64)> = histories
        .iter()
        .enumerate()
        .filter_map(|(i, h)| h.1.iter().rev().find(|v| v.is_finite()).map(|v| (i, *v)))
        .collect();
    last.sort_by(|a, b| b.1.total_cmp(&a.1));
    last.into_iter().take(k).map(|(i, _)| i).collect()
}

/// Bins of [`SubjectReport::scaled_jacobian_histogram`].
pub const JACOBIAN_BINS: usize = 40;

/// Counts of scaled Jacobians in [`JACOBIAN_BINS`] bins over [-1, 1].
pub fn jacobian_histogram(values: impl IntoIterator<Item = f64>) -> Vec<u32> {
    let mut h = vec![0u32; JACOBIAN_BINS];
    for v in values {
        if v.is_finite() {
            let k = (((v + 1.0) / 2.0 * JACOBIAN_BINS as f64).floor() as i64)
                .clamp(0, JACOBIAN_BINS as i64 - 1);
            h[k as usize] += 1;
        }
    }
    h
}

/// Histogram of the scaled Jacobians of all subjects' elements (counts summed over subjects).
pub fn plot_jacobian_histogram(path: &Path, counts: &[u32]) -> Result<()> {
    let text = super::render::font_available();
    Canvas::new(720, 460).draw(path, |root| {
        root.fill(&WHITE).map_err(perr(path))?;
        let top = counts.iter().copied().max().unwrap_or(1).max(1) as f64;
        let mut chart = chart_frame(&root, "Scaled Jacobians of all morphed meshes", 64, text)
            .build_cartesian_2d(-1f64..1f64, 0f64..top * 1.05)
            .map_err(perr(path))?;
        if text {
            chart
                .configure_mesh()
                .x_desc("smallest corner scaled Jacobian of an element")
                .y_desc("elements")
                .draw()
                .map_err(perr(path))?;
        }
        let w = 2.0 / counts.len().max(1) as f64;
        chart
            .draw_series(counts.iter().enumerate().map(|(k, &c)| {
                let x0 = -1.0 + w * k as f64;
                Rectangle::new(
                    [(x0, 0.0), (x0 + w, c as f64)],
                    jacobian_color(x0 + 0.5 * w).filled(),
                )
            }))
            .map_err(perr(path))?;
        Ok(())
    })
}

/// Colour of a scaled Jacobian in [-1, 1] ([`render::jacobian_color`]).
fn jacobian_color(s: f64) -> RGBColor {
    let [r, g, b] = render::jacobian_color(s);
    RGBColor(r, g, b)
}

/// Per-subject figure (fig. 9): left, the mean (red), the subject (blue) and the locus of the
/// instance (green), all in the subject frame; right, the morphed mesh coloured by scaled
/// Jacobian. Outlines are lists of polylines.
pub fn plot_subject(
    path: &Path,
    title: &str,
    mean: &[Point<2>],
    subject: &[Point<2>],
    locus: &[Vec<Point<2>>],
    mesh: &FeMesh<2>,
    closed: bool,
) -> Result<()> {
    let text = super::render::font_available();
    Canvas::new(1100, 540).draw(path, |root| {
        root.fill(&WHITE).map_err(perr(path))?;
        let (left, right) = root.split_horizontally(550);
        let mut all: Vec<Point<2>> = subject.to_vec();
        all.extend_from_slice(mean);
        all.extend(locus.iter().flatten().copied());
        all.extend_from_slice(&mesh.nodes);
        let (lo, hi) = bounding_box(&all);
        let ext = (hi[0] - lo[0]).max(hi[1] - lo[1]) * 0.55 + 1e-12;
        let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
        // y up, as the mesh files show in ParaView or Gmsh.
        let panel = Panel {
            path,
            text,
            xr: c[0] - ext..c[0] + ext,
            yr: c[1] - ext..c[1] + ext,
            closed,
        };
        panel.fit(&left, title, mean, subject, locus)?;
        // The mesh panel, with its colour bar under it.
        let (right, bar) = right.split_vertically(500);
        panel.jacobian_bar(&bar)?;
        panel.mesh(&right, title, mesh, subject)
    })
}

/// A picture's drawing area.
type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// What the panels of a subject's figure share: the file (for messages), whether there is a
/// font, the common axes, whether outlines close.
struct Panel<'p> {
    path: &'p Path,
    text: bool,
    xr: std::ops::Range<f64>,
    yr: std::ops::Range<f64>,
    closed: bool,
}

impl Panel<'_> {
    /// An outline as plotters' points, closed when the outlines are.
    fn line(&self, pts: &[Point<2>]) -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = pts.iter().map(|p| (p[0], p[1])).collect();
        if self.closed
            && let Some(f) = v.first().copied()
        {
            v.push(f);
        }
        v
    }

    /// The fit: the locus of the instance, the mean and the subject, with their legend.
    fn fit(
        &self,
        area: &Area<'_>,
        title: &str,
        mean: &[Point<2>],
        subject: &[Point<2>],
        locus: &[Vec<Point<2>>],
    ) -> Result<()> {
        let path = self.path;
        let mut b = ChartBuilder::on(area);
        b.margin(10);
        if self.text {
            b.caption(format!("{title}: fit"), ("sans-serif", 18));
        }
        let mut ch = b
            .build_cartesian_2d(self.xr.clone(), self.yr.clone())
            .map_err(perr(path))?;
        for (k, l) in locus.iter().enumerate() {
            let s = ch
                .draw_series(LineSeries::new(
                    self.line(l),
                    GREEN.mix(0.5).stroke_width(1),
                ))
                .map_err(perr(path))?;
            if k == 0 {
                s.label("locus of the fit").legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], GREEN.mix(0.5).stroke_width(2))
                });
            }
        }
        ch.draw_series(LineSeries::new(self.line(mean), RED.stroke_width(2)))
            .map_err(perr(path))?
            .label("mean")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
        ch.draw_series(LineSeries::new(self.line(subject), BLUE.stroke_width(2)))
            .map_err(perr(path))?
            .label("subject")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
        if self.text {
            ch.configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK.mix(0.4))
                .label_font(("sans-serif", 14))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(perr(path))?;
        }
        Ok(())
    }

    /// The scaled Jacobian's colour bar.
    fn jacobian_bar(&self, bar: &Area<'_>) -> Result<()> {
        let path = self.path;
        let (x0, x1) = (120i32, 430i32);
        for x in x0..x1 {
            let s = f64::from(x - x0) / f64::from(x1 - x0 - 1);
            bar.draw(&Rectangle::new(
                [(x, 6), (x + 1, 18)],
                jacobian_color(s.max(1e-6)).filled(),
            ))
            .map_err(perr(path))?;
        }
        if self.text {
            let font = ("sans-serif", 13).into_font().color(&BLACK);
            bar.draw(&Text::new(
                "scaled Jacobian: ≤ 0",
                (x0 - 118, 5),
                font.clone(),
            ))
            .map_err(perr(path))?;
            bar.draw(&Text::new("0.5", ((x0 + x1) / 2 - 8, 21), font.clone()))
                .map_err(perr(path))?;
            bar.draw(&Text::new("1", (x1 + 6, 5), font))
                .map_err(perr(path))?;
        }
        Ok(())
    }

    /// The mesh, each element coloured by its scaled Jacobian, over the subject's outline.
    fn mesh(
        &self,
        area: &Area<'_>,
        title: &str,
        mesh: &FeMesh<2>,
        subject: &[Point<2>],
    ) -> Result<()> {
        let path = self.path;
        let mut b = ChartBuilder::on(area);
        b.margin(10);
        if self.text {
            b.caption(
                format!("{title}: mesh (scaled Jacobian)"),
                ("sans-serif", 18),
            );
        }
        let mut ch = b
            .build_cartesian_2d(self.xr.clone(), self.yr.clone())
            .map_err(perr(path))?;
        let q = mesh_quality(mesh);
        let corners = |e: usize| -> Vec<(f64, f64)> {
            mesh.element(e)
                .iter()
                .map(|&i| (mesh.nodes[i][0], mesh.nodes[i][1]))
                .collect()
        };
        ch.draw_series((0..mesh.num_elements()).map(|e| {
            Polygon::new(
                corners(e),
                jacobian_color(q[e].scaled_jacobian_min).filled(),
            )
        }))
        .map_err(perr(path))?;
        ch.draw_series((0..mesh.num_elements()).map(|e| {
            let mut pts = corners(e);
            pts.push(pts[0]);
            PathElement::new(pts, BLACK.mix(0.6).stroke_width(1))
        }))
        .map_err(perr(path))?;
        ch.draw_series(LineSeries::new(
            self.line(subject),
            BLUE.mix(0.7).stroke_width(1),
        ))
        .map_err(perr(path))?;
        Ok(())
    }
}

/// The mean shape and the instances at -2σ and +2σ along each of the first 3 modes (figs. 4
/// and 15), in the reference frame. 2D: one panel per mode, the mean black, -2σ blue, +2σ
/// red. 3D: a row per mode (-2σ, mean, +2σ), shaded renders coloured by each point's
/// displacement from its place on the mean along the mean's outward normal (blue inwards,
/// white 0, red outwards; the row's largest at the ends of its colour bar).
pub fn plot_modes<const D: usize>(path: &Path, atlas: &crate::model::Atlas<D>) -> Result<()> {
    let modes = atlas.num_modes().min(3);
    let at = |m: usize, k: f64| -> Vec<Point<D>> {
        let mut w = vec![0.0; atlas.num_modes()];
        w[m] = k * atlas.eigenvalues[m].max(0.0).sqrt();
        atlas.instance(&w)
    };
    if D == 3 {
        return plot_modes_3d(path, atlas, modes, at);
    }
    let text = super::render::font_available();
    Canvas::new(360 * modes as u32, 380).draw(path, |root| {
        root.fill(&WHITE).map_err(perr(path))?;
        let (lo, hi) = bounding_box(&atlas.mean);
        let pad = 0.25 * (0..D).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
        let (cx, cy) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
        let half = 0.5 * (hi[0] - lo[0]).max(hi[1] - lo[1]) + pad;
        for (m, area) in root.split_evenly((1, modes)).iter().enumerate() {
            let mut b = ChartBuilder::on(area);
            b.margin(8);
            if text {
                b.caption(
                    format!("mode {}: -2σ, mean, +2σ", m + 1),
                    ("sans-serif", 16),
                );
            }
            let mut chart = b
                .build_cartesian_2d(cx - half..cx + half, cy - half..cy + half)
                .map_err(perr(path))?;
            for (shape, color, label) in [
                (at(m, -2.0), BLUE.to_rgba(), "-2σ"),
                (atlas.mean.clone(), BLACK.to_rgba(), "mean"),
                (at(m, 2.0), RED.to_rgba(), "+2σ"),
            ] {
                chart
                    .draw_series(atlas.facets.iter().map(|f| {
                        PathElement::new(
                            f.iter()
                                .map(|&i| (shape[i][0], shape[i][1]))
                                .collect::<Vec<_>>(),
                            color.stroke_width(2),
                        )
                    }))
                    .map_err(perr(path))?
                    .label(label)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
            }
            if text {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK.mix(0.4))
                    .label_font(("sans-serif", 13))
                    .position(SeriesLabelPosition::LowerRight)
                    .draw()
                    .map_err(perr(path))?;
            }
        }
        Ok(())
    })
}

/// [`plot_modes`] of a 3D atlas: a row per mode (-2σ, mean, +2σ), shaded renders coloured by
/// the displacement along the mean's outward normal; `at(m, k)` the instance at `k` σ of
/// mode `m`.
fn plot_modes_3d<const D: usize>(
    path: &Path,
    atlas: &crate::model::Atlas<D>,
    modes: usize,
    at: impl Fn(usize, f64) -> Vec<Point<D>>,
) -> Result<()> {
    use render::{Image, Legend, View, annotated, render, signed_color};
    let to3 = |v: &[Point<D>]| -> Vec<Point<3>> {
        v.iter().map(|p| std::array::from_fn(|d| p[d])).collect()
    };
    let tris: Vec<[usize; 3]> = atlas
        .facets
        .iter()
        .map(|f| std::array::from_fn(|k| f[k.min(D - 1)]))
        .collect();
    let mean_shape = atlas.mean_shape();
    let normals = mean_shape.vertex_normals();
    let mean = to3(&atlas.mean);
    let view = View::fitting(&mean);
    let (w, h) = (320, 240);
    let mut tiles = Vec::new();
    for m in 0..modes {
        let shapes = [to3(&at(m, -2.0)), mean.clone(), to3(&at(m, 2.0))];
        // Displacement from the mean along its outward normal, in the reference frame
        // (the mean's largest side is 1).
        let moved: Vec<Vec<f64>> = shapes
            .iter()
            .map(|s| {
                s.iter()
                    .zip(&mean)
                    .zip(&normals)
                    .map(|((a, b), n)| (0..3).map(|d| (a[d] - b[d]) * n[d.min(D - 1)]).sum::<f64>())
                    .collect()
            })
            .collect();
        let max = moved
            .iter()
            .flatten()
            .fold(0.0f64, |a, b| a.max(b.abs()))
            .max(f64::MIN_POSITIVE);
        let color = signed_color(max);
        let legend = Legend {
            color: &color,
            lo: -max,
            hi: max,
            lo_label: format!("in {:.1} %", 100.0 * max),
            hi_label: format!("out {:.1} %", 100.0 * max),
        };
        for (c, (s, d)) in shapes.iter().zip(&moved).enumerate() {
            let title = match c {
                0 => format!("mode {}: -2σ", m + 1),
                1 => "mean; normal displacement, % of size".to_string(),
                _ => format!("mode {}: +2σ", m + 1),
            };
            let picture = render(s, &tris, Some(d), None, &color, &view, w, h);
            tiles.push(annotated(&picture, &title, Some(&legend)));
        }
    }
    let th = tiles.first().map_or(h, |t| t.height);
    let mut img = Image::new(3 * w, modes * th);
    for (k, t) in tiles.iter().enumerate() {
        img.paste(t, (k % 3) * w, (k / 3) * th);
    }
    crate::formats::write_atomic(path, &img.png()?)
}

/// The paper's comparison (fig. 12/20): per subject (sorted by the SSM fit's value) the
/// normal correlation (eq. 13) of the SSM fit's correspondence, of the FFD registration's and
/// of the similarity ICP's.
pub fn plot_baselines(path: &Path, subjects: &[SubjectReport]) -> Result<()> {
    let text = super::render::font_available();
    let mut rows: Vec<(f64, f64, f64)> = subjects
        .iter()
        .map(|s| {
            (
                s.normal_correlation,
                s.normal_correlation_ffd.unwrap_or(f64::NAN),
                s.normal_correlation_icp.unwrap_or(f64::NAN),
            )
        })
        .collect();
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let lo = rows
        .iter()
        .flat_map(|r| [r.0, r.1, r.2])
        .filter(|v| v.is_finite())
        .fold(1.0f64, f64::min)
        .min(0.99)
        - 0.01;
    Canvas::new(720, 420).draw(path, |root| {
        root.fill(&WHITE).map_err(perr(path))?;
        let mut chart = chart_frame(&root, "normal correlation per subject", 56, text)
            .build_cartesian_2d(0.0..rows.len().max(1) as f64, lo..1.0)
            .map_err(perr(path))?;
        if text {
            chart
                .configure_mesh()
                .x_desc("subjects (sorted by the SSM fit)")
                .y_desc("normal correlation")
                .draw()
                .map_err(perr(path))?;
        }
        type Series = (&'static str, RGBColor, fn(&(f64, f64, f64)) -> f64);
        let series: [Series; 3] = [
            ("SSM fit", RGBColor(200, 30, 30), |r| r.0),
            ("FFD registration", RGBColor(30, 90, 200), |r| r.1),
            ("similarity ICP", RGBColor(90, 90, 90), |r| r.2),
        ];
        for (name, color, get) in series {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .enumerate()
                .map(|(i, r)| (i as f64 + 0.5, get(r)))
                .filter(|p| p.1.is_finite())
                .collect();
            let s = chart
                .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                .map_err(perr(path))?;
            if text {
                s.label(name).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2))
                });
            }
        }
        if text {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .position(SeriesLabelPosition::LowerRight)
                .draw()
                .map_err(perr(path))?;
        }
        Ok(())
    })
}

/// Histogram of the elements' Young's modulus (MPa) of a material map, titled `title`.
pub fn plot_modulus_histogram(
    path: &Path,
    histogram: &crate::materials::Histogram,
    title: &str,
) -> Result<()> {
    let text = super::render::font_available();
    let (Some(&lo), Some(&hi)) = (histogram.edges.first(), histogram.edges.last()) else {
        return Err(crate::Error::Parameter(format!(
            "{}: an empty histogram",
            path.display()
        )));
    };
    let hi = if hi > lo { hi } else { lo + 1.0 };
    Canvas::new(720, 400).draw(path, |root| {
        root.fill(&WHITE).map_err(perr(path))?;
        let top = histogram.counts.iter().copied().max().unwrap_or(1).max(1) as f64;
        let mut chart = chart_frame(&root, title, 64, text)
            .build_cartesian_2d(lo..hi, 0f64..top * 1.05)
            .map_err(perr(path))?;
        if text {
            chart
                .configure_mesh()
                .x_desc("Young's modulus E of an element (MPa)")
                .y_desc("elements")
                .x_label_formatter(&|x| format!("{x:.0}"))
                .y_label_formatter(&|y| format!("{y:.0}"))
                .draw()
                .map_err(perr(path))?;
        }
        chart
            .draw_series(histogram.counts.iter().enumerate().map(|(k, &c)| {
                let (x0, x1) = (histogram.edges[k], histogram.edges[k + 1]);
                Rectangle::new([(x0, 0.0), (x1, c as f64)], RGBColor(70, 110, 170).filled())
            }))
            .map_err(perr(path))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn count_axes_label_integers_only() {
        assert_eq!(integer_label(&2.0), "2");
        assert_eq!(integer_label(&2.5), "");
        assert_eq!(integer_label(&0.0), "0");
        assert_eq!(integer_label(&(3.0 + 1e-12)), "3");
    }

    #[test]
    fn the_e_d_plot_names_the_subjects_that_ended_highest() {
        let h: Vec<(String, Vec<f64>)> = (0..10)
            .map(|k| (format!("s{k}"), vec![100.0, (k * 7 % 10) as f64 + 1.0]))
            .collect();
        let named = highest_last(&h, 3);
        let last: Vec<f64> = named.iter().map(|&i| h[i].1[1]).collect();
        assert_eq!(last, vec![10.0, 9.0, 8.0]);
        assert_eq!(highest_last(&h[..2], 6).len(), 2);
        // A history with no finite value is left out.
        assert!(highest_last(&[("x".into(), vec![f64::NAN])], 6).is_empty());
    }
}
