//! Figures as PNG and SVG with plotters, rendered with the committed DejaVu Sans font
//! (`data/fonts/DejaVuSans.ttf`, registered with plotters' ab_glyph backend), so they render
//! the same on any machine without system fonts.
//!
//! Log axes are drawn as linear axes in log10 of the data with `1eN` tick labels, which keeps
//! one code path for every panel. Files are written atomically (PNG: drawn to a temporary
//! file in the destination folder, then renamed).

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use crate::io::write_atomic;
use crate::sweep::{Result, StudyError};

static FONT: &[u8] = include_bytes!("../../../data/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the committed font as "sans-serif" (once per process).
pub fn register_fonts() {
    REGISTER.call_once(|| {
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Tableau-10 colours.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    None,
    Circle,
    Triangle,
    Cross,
    Square,
}

/// A data series of an x–y panel.
#[derive(Debug, Clone)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub color: usize,
    pub line: bool,
    pub dashed: bool,
    pub marker: Marker,
    pub width: u32,
}

impl Series {
    pub fn line(name: &str, points: Vec<(f64, f64)>, color: usize) -> Self {
        Series {
            name: name.into(),
            points,
            color,
            line: true,
            dashed: false,
            marker: Marker::None,
            width: 2,
        }
    }
    pub fn points(name: &str, points: Vec<(f64, f64)>, color: usize, marker: Marker) -> Self {
        Series {
            name: name.into(),
            points,
            color,
            line: false,
            dashed: false,
            marker,
            width: 2,
        }
    }
    pub fn marker(mut self, m: Marker) -> Self {
        self.marker = m;
        self
    }
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
    pub fn width(mut self, w: u32) -> Self {
        self.width = w;
        self
    }
}

/// A vertical marker line with a label.
#[derive(Debug, Clone)]
pub struct VLine {
    pub x: f64,
    pub label: String,
    pub color: usize,
}

/// An x–y panel.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
    pub vlines: Vec<VLine>,
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
    /// Legend position: true = upper right, false = upper left.
    pub legend_right: bool,
    pub no_legend: bool,
}

/// A heat map on a grid of (x, y) values (both optionally log), one cell per point.
#[derive(Debug, Clone, Default)]
pub struct Heat {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    /// (x, y, value); None = failed run (grey cell marked "x").
    pub cells: Vec<(f64, f64, Option<f64>)>,
    /// Colour scale in log10 of the value.
    pub log_value: bool,
    /// Value range of the colour scale (in the value's units).
    pub value_range: (f64, f64),
}

#[derive(Debug, Clone)]
pub enum PanelKind {
    Xy(Panel),
    Heat(Heat),
}

fn tr(v: f64, log: bool) -> f64 {
    if log {
        v.log10()
    } else {
        v
    }
}

fn tick_label(v: f64, log: bool) -> String {
    if log {
        if (v - v.round()).abs() < 1e-9 {
            format!("1e{}", v.round() as i64)
        } else {
            let x = 10f64.powf(v);
            format!("{x:.2e}")
        }
    } else {
        let a = v.abs();
        if a < 1e-12 {
            return "0".into();
        }
        if a != 0.0 && !(1e-3..1e5).contains(&a) {
            format!("{v:.1e}")
        } else {
            let s = format!("{v:.4}");
            let s = s.trim_end_matches('0').trim_end_matches('.');
            if s == "-0" {
                "0".into()
            } else {
                s.to_string()
            }
        }
    }
}

fn bounds(vals: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return None;
    }
    if hi - lo < 1e-12 * (1.0 + hi.abs()) {
        return Some((lo - 0.5 - 0.05 * lo.abs(), hi + 0.5 + 0.05 * hi.abs()));
    }
    let pad = 0.05 * (hi - lo);
    Some((lo - pad, hi + pad))
}

type DErr = String;

fn err<E: std::fmt::Debug>(e: E) -> DErr {
    format!("{e:?}")
}

fn draw_xy<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
) -> std::result::Result<(), DErr> {
    let pts = |s: &Series| -> Vec<(f64, f64)> {
        s.points
            .iter()
            .map(|&(x, y)| (tr(x, p.log_x), tr(y, p.log_y)))
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect()
    };
    let all: Vec<(f64, f64)> = p.series.iter().flat_map(pts).collect();
    let xr = p
        .x_range
        .map(|(a, b)| (tr(a, p.log_x), tr(b, p.log_x)))
        .or_else(|| {
            bounds(
                all.iter()
                    .map(|q| q.0)
                    .chain(p.vlines.iter().map(|v| tr(v.x, p.log_x))),
            )
        })
        .unwrap_or((0.0, 1.0));
    let yr = p
        .y_range
        .map(|(a, b)| (tr(a, p.log_y), tr(b, p.log_y)))
        .or_else(|| bounds(all.iter().map(|q| q.1)))
        .unwrap_or((0.0, 1.0));
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 17))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(62)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
        .map_err(err)?;
    let (lx, ly) = (p.log_x, p.log_y);
    let xf = move |v: &f64| tick_label(*v, lx);
    let yf = move |v: &f64| tick_label(*v, ly);
    chart
        .configure_mesh()
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 14))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()
        .map_err(err)?;
    for v in &p.vlines {
        let x = tr(v.x, p.log_x);
        if !x.is_finite() {
            continue;
        }
        let c = color(v.color);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x, yr.0), (x, yr.1)],
                6,
                4,
                c.stroke_width(1),
            ))
            .map_err(err)?
            .label(v.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(1)));
    }
    for s in &p.series {
        let c = color(s.color);
        let data = pts(s);
        let style = c.stroke_width(s.width);
        let named = !s.name.is_empty();
        let name = s.name.clone();
        if s.line {
            let a = if s.dashed {
                chart
                    .draw_series(DashedLineSeries::new(data.clone(), 8, 5, style))
                    .map_err(err)?
            } else {
                chart
                    .draw_series(LineSeries::new(data.clone(), style))
                    .map_err(err)?
            };
            if named {
                a.label(name.clone()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
            }
        }
        let label_markers = named && !s.line;
        let ms = 4;
        match s.marker {
            Marker::None => {}
            Marker::Circle => {
                let a = chart
                    .draw_series(data.iter().map(|&q| Circle::new(q, ms, c.filled())))
                    .map_err(err)?;
                if label_markers {
                    a.label(name.clone())
                        .legend(move |(x, y)| Circle::new((x + 9, y), 4, c.filled()));
                }
            }
            Marker::Square => {
                let a = chart
                    .draw_series(data.iter().map(|&q| {
                        EmptyElement::at(q) + Rectangle::new([(-ms, -ms), (ms, ms)], c.filled())
                    }))
                    .map_err(err)?;
                if label_markers {
                    a.label(name.clone()).legend(move |(x, y)| {
                        Rectangle::new([(x + 5, y - 4), (x + 13, y + 4)], c.filled())
                    });
                }
            }
            Marker::Triangle => {
                let a = chart
                    .draw_series(
                        data.iter()
                            .map(|&q| TriangleMarker::new(q, ms + 1, c.filled())),
                    )
                    .map_err(err)?;
                if label_markers {
                    a.label(name.clone())
                        .legend(move |(x, y)| TriangleMarker::new((x + 9, y), 5, c.filled()));
                }
            }
            Marker::Cross => {
                let a = chart
                    .draw_series(data.iter().map(|&q| Cross::new(q, ms, c.stroke_width(2))))
                    .map_err(err)?;
                if label_markers {
                    a.label(name.clone())
                        .legend(move |(x, y)| Cross::new((x + 9, y), 4, c.stroke_width(2)));
                }
            }
        }
    }
    if !p.no_legend && (p.series.iter().any(|s| !s.name.is_empty()) || !p.vlines.is_empty()) {
        chart
            .configure_series_labels()
            .position(if p.legend_right {
                SeriesLabelPosition::UpperRight
            } else {
                SeriesLabelPosition::UpperLeft
            })
            .label_font(("sans-serif", 12))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

/// Viridis-like colour for t in [0, 1].
pub fn ramp(t: f64) -> RGBColor {
    const STOPS: [(f64, (f64, f64, f64)); 5] = [
        (0.0, (68.0, 1.0, 84.0)),
        (0.25, (59.0, 82.0, 139.0)),
        (0.5, (33.0, 145.0, 140.0)),
        (0.75, (94.0, 201.0, 98.0)),
        (1.0, (253.0, 231.0, 37.0)),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    for w in STOPS.windows(2) {
        let ((a, ca), (b, cb)) = (w[0], w[1]);
        if t <= b {
            let s = (t - a) / (b - a);
            let m = |x: f64, y: f64| (x + s * (y - x)).round() as u8;
            return RGBColor(m(ca.0, cb.0), m(ca.1, cb.1), m(ca.2, cb.2));
        }
    }
    RGBColor(253, 231, 37)
}

/// Distinct sorted grid values with the edges of their cells: (value, low edge, high edge),
/// edges at midpoints between neighbours, the outer cells as wide as their inner half.
fn cell_edges(v: &[f64]) -> Vec<(f64, f64, f64)> {
    let mut u: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    u.sort_by(f64::total_cmp);
    u.dedup();
    let n = u.len();
    (0..n)
        .map(|i| {
            let lo = if i > 0 {
                0.5 * (u[i - 1] + u[i])
            } else if n > 1 {
                u[0] - 0.5 * (u[1] - u[0])
            } else {
                u[0] - 0.5
            };
            let hi = if i + 1 < n {
                0.5 * (u[i] + u[i + 1])
            } else if n > 1 {
                u[i] + 0.5 * (u[i] - u[i - 1])
            } else {
                u[0] + 0.5
            };
            (u[i], lo, hi)
        })
        .collect()
}

fn draw_heat<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    h: &Heat,
) -> std::result::Result<(), DErr> {
    let xs: Vec<f64> = h.cells.iter().map(|c| tr(c.0, h.log_x)).collect();
    let ys: Vec<f64> = h.cells.iter().map(|c| tr(c.1, h.log_y)).collect();
    // Cells tile the plane: each spans to the midpoints between its grid neighbours, so a
    // non-uniform grid (1e-2, 5e-3, 2e-3 … on a log axis) leaves no gaps.
    let (xe, ye) = (cell_edges(&xs), cell_edges(&ys));
    let span = |v: f64, e: &[(f64, f64, f64)]| {
        e.iter()
            .find(|c| c.0 == v)
            .map_or((v - 0.5, v + 0.5), |c| (c.1, c.2))
    };
    let x0 = xe.first().map_or(0.0, |c| c.1);
    let x1 = xe.last().map_or(1.0, |c| c.2);
    let y0 = ye.first().map_or(0.0, |c| c.1);
    let y1 = ye.last().map_or(1.0, |c| c.2);
    let mut chart = ChartBuilder::on(area)
        .caption(&h.title, ("sans-serif", 17))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(62)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    let (lx, ly) = (h.log_x, h.log_y);
    let xf = move |v: &f64| tick_label(*v, lx);
    let yf = move |v: &f64| tick_label(*v, ly);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(h.x_label.as_str())
        .y_desc(h.y_label.as_str())
        .x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    let (lo, hi) = (
        tr(h.value_range.0, h.log_value),
        tr(h.value_range.1, h.log_value),
    );
    for (i, c) in h.cells.iter().enumerate() {
        let ((xl, xh), (yl, yh)) = (span(xs[i], &xe), span(ys[i], &ye));
        let (fill, text) = match c.2 {
            Some(v) if v.is_finite() => {
                let t = (tr(v.max(1e-300), h.log_value) - lo) / (hi - lo);
                (ramp(t), format!("{v:.0e}"))
            }
            _ => (RGBColor(200, 200, 200), "fail".to_string()),
        };
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(xl, yl), (xh, yh)],
                fill.filled(),
            )))
            .map_err(err)?;
        let dark = matches!(c.2, Some(v) if v.is_finite() && (tr(v.max(1e-300), h.log_value) - lo) / (hi - lo) < 0.6);
        let tc = if dark { WHITE } else { BLACK };
        chart
            .draw_series(std::iter::once(Text::new(
                text,
                (xl + 0.2 * (xh - xl), 0.5 * (yl + yh)),
                ("sans-serif", 11).into_font().color(&tc),
            )))
            .map_err(err)?;
    }
    Ok(())
}

fn draw_all<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    rows: usize,
    cols: usize,
    panels: &[PanelKind],
    caption: &str,
) -> std::result::Result<(), DErr> {
    root.fill(&WHITE).map_err(err)?;
    let body = if caption.is_empty() {
        root.clone()
    } else {
        let (_, h) = root.dim_in_pixel();
        let (top, bottom) = root.split_vertically(h as i32 - 34);
        bottom
            .draw_text(
                caption,
                &("sans-serif", 13).into_font().color(&RGBColor(60, 60, 60)),
                (10, 10),
            )
            .map_err(err)?;
        top
    };
    let areas = body.split_evenly((rows, cols));
    for (a, p) in areas.iter().zip(panels) {
        match p {
            PanelKind::Xy(p) => draw_xy(a, p)?,
            PanelKind::Heat(h) => draw_heat(a, h)?,
        }
    }
    root.present().map_err(err)?;
    Ok(())
}

/// Draws `panels` on a `rows × cols` grid with an optional caption line at the bottom and
/// writes `<dir>/<stem>.png` and `<dir>/<stem>.svg`.
pub fn figure(
    dir: &Path,
    stem: &str,
    size: (u32, u32),
    (rows, cols): (usize, usize),
    panels: &[PanelKind],
    caption: &str,
) -> Result<()> {
    register_fonts();
    std::fs::create_dir_all(dir)
        .map_err(|e| StudyError::Other(format!("{}: {e}", dir.display())))?;
    let fail = |what: &str, e: String| StudyError::Other(format!("figure {stem}.{what}: {e}"));
    // PNG: draw into a temporary file (the extension picks the encoder), then rename.
    let png = dir.join(format!("{stem}.png"));
    let tmp = dir.join(format!(".{stem}.tmp-{}.png", std::process::id()));
    {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        if let Err(e) = draw_all(&root, rows, cols, panels, caption) {
            let _ = std::fs::remove_file(&tmp);
            return Err(fail("png", e));
        }
    }
    std::fs::rename(&tmp, &png).map_err(|e| fail("png", e.to_string()))?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_all(&root, rows, cols, panels, caption).map_err(|e| fail("svg", e))?;
    }
    write_atomic(&dir.join(format!("{stem}.svg")), svg.as_bytes())?;
    Ok(())
}
