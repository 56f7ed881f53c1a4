//! Figures as PNG and SVG with plotters.
//!
//! Text: every string is drawn from the glyph outlines of the committed DejaVu Sans font
//! (`data/fonts/DejaVuSans.ttf`, see `plot/text.rs`): rasterised in the PNG, glyph paths in the SVG
//! (no `<text>` element), so both render the same on any machine and viewer.
//!
//! Size: `figure` takes the pixel width from its `size` argument and derives every text and
//! stroke size from it. The smallest text has an em of 0.035 × the width, so a figure printed
//! 85 mm wide shows it at 8.5 pt (≥ 8 pt needs ≥ [`MIN_TEXT_FRACTION`] = 0.0332). The height
//! follows from the layout: titles, axis descriptions and captions wrap; legends go below each
//! panel, or below all panels when the figure has a single legend or its panels repeat
//! entries; each plot area keeps the aspect ratio asked for by `size` (clamped to 0.4 … 0.85)
//! and the panels of a row are aligned. A y description that does not fit beside the plot in
//! two rotated lines is set horizontally above the plot (for every panel of the figure), and
//! side-by-side panels whose plots would be narrower than 7 em are stacked in one column:
//! figures grow taller rather than wider.
//!
//! Axes: log axes are linear axes in log10 of the data, ticked at whole decades (every k-th
//! when space is short) when three or more fit, else at 1-3-10 or 1-2-5 × 10ⁿ, else at round
//! steps of the values; labelled 0.001 … 1000 when every tick lies in that range and
//! 10⁻⁶-style otherwise. Linear axes get 1-2-2.5-5 × 10ⁿ steps (whole numbers only when the
//! data are whole numbers), with a common ×10ⁿ form for very large or small values. Heat maps
//! tick the grid values and have a colour bar; their cells carry their value when every label
//! fits its cell. Files are written atomically (PNG: drawn to a temporary file in the
//! destination folder, then renamed).

mod text;

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle, FontTransform};
use plotters_backend::text_anchor::{HPos, Pos, VPos};

use crate::io::write_atomic;
use crate::sweep::{Result, StudyError};

pub use text::units_per_em;
use text::{OutlineText, FONT_DATA};

static REGISTER: Once = Once::new();

/// Registers the committed font as "sans-serif" (once per process). plotters needs a
/// registered font to build its text styles; the drawing itself goes through `plot/text.rs`.
pub fn register_fonts() {
    REGISTER.call_once(|| {
        let _ = register_font("sans-serif", FontStyle::Normal, FONT_DATA);
    });
}

/// Smallest em size of any text as a fraction of the figure width for 8 pt at 85 mm print
/// width: 8 pt × 25.4 / 72 mm ÷ 85 mm = 0.0332.
pub const MIN_TEXT_FRACTION: f64 = 0.0332;

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
    /// (x, y, value); None = failed run (grey cell crossed out).
    pub cells: Vec<(f64, f64, Option<f64>)>,
    /// Colour scale in log10 of the value.
    pub log_value: bool,
    /// Value range of the colour scale (in the value's units); values outside take the
    /// end colours.
    pub value_range: (f64, f64),
    /// Label of the colour bar (with unit); empty: none.
    pub value_label: String,
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

// ---------------------------------------------------------------------------------------
// Tick labels.

/// `n` with Unicode superscript digits and minus (10⁻⁶).
fn superscript(n: i32) -> String {
    n.to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            '9' => '⁹',
            c => c,
        })
        .collect()
}

/// `v` with `dec` decimals, "-0" written as "0".
fn fixed(v: f64, dec: usize) -> String {
    let s = format!("{v:.dec$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0".into()
    } else {
        // A typographic minus sign.
        s.replace('-', "−")
    }
}

/// Decimal exponent and mantissa of |v| > 0 rounded to `sig` significant digits.
fn sci(v: f64, sig: i32) -> (i32, f64) {
    let mut e = v.abs().log10().floor() as i32;
    let q = 10f64.powi(sig - 1);
    let mut m = (v / 10f64.powi(e) * q).round() / q;
    if m.abs() >= 10.0 {
        m /= 10.0;
        e += 1;
    }
    (e, m)
}

/// One value with two significant digits: plain decimal, or m×10ⁿ when `plain` is false.
fn value_text(v: f64, plain: bool) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { v.to_string() };
    }
    let (e, m) = sci(v, 2);
    let mant_dec = if (m * 10.0).round() % 10.0 == 0.0 {
        0
    } else {
        1
    };
    if plain {
        fixed(m * 10f64.powi(e), (mant_dec - e).max(0) as usize)
    } else if m == 1.0 {
        format!("10{}", superscript(e))
    } else if m == -1.0 {
        format!("−10{}", superscript(e))
    } else {
        format!("{}×10{}", fixed(m, mant_dec as usize), superscript(e))
    }
}

/// Whether values whose decimal exponents lie in `lo ..= hi` read well as plain decimals.
fn plain_range(lo: i32, hi: i32) -> bool {
    lo >= -3 && hi <= 3
}

/// A tick: position in plot coordinates (log10 of the value on log axes) and its label.
type Tick = (f64, String);

/// Round linear ticks in [lo, hi], about `n` of them.
fn linear_ticks(lo: f64, hi: f64, n: usize) -> Vec<Tick> {
    let raw = (hi - lo) / n.max(1) as f64;
    if !(raw > 0.0 && raw.is_finite()) {
        return vec![];
    }
    let mut e = raw.log10().floor() as i32;
    let f = raw / 10f64.powi(e);
    let mut m = [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .find(|&m| f <= m * (1.0 + 1e-9))
        .unwrap_or(10.0);
    if m == 10.0 {
        m = 1.0;
        e += 1;
    }
    let step = m * 10f64.powi(e);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    let vals: Vec<f64> = (first..=last).map(|i| i as f64 * step).collect();
    let extra = i32::from(m == 2.5);
    let amax = vals.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if amax >= 1e5 || (amax > 0.0 && amax < 1e-3) {
        let p = amax.log10().floor() as i32;
        let dec = (p - e + extra).max(0) as usize;
        vals.iter()
            .map(|&v| {
                let t = if v.abs() < 1e-9 * step {
                    "0".to_string()
                } else {
                    format!("{}×10{}", fixed(v / 10f64.powi(p), dec), superscript(p))
                };
                (v, t)
            })
            .collect()
    } else {
        let dec = (extra - e).max(0) as usize;
        vals.iter().map(|&v| (v, fixed(v, dec))).collect()
    }
}

/// Ticks of a log axis spanning log10 values [lo, hi]: the candidate with the most ticks,
/// at most `n` of them, from whole decades (every decade, or every k-th), 1-3-10, 1-2-5 and
/// round linear steps of the values, preferred in that order on a tie; with the light grid
/// lines (2 … 9 × 10ⁿ) when every decade is ticked.
fn log_ticks(lo: f64, hi: f64, n: usize) -> (Vec<Tick>, Vec<f64>) {
    let (a, b) = ((lo - 1e-9).ceil() as i32, (hi + 1e-9).floor() as i32);
    let inside = |x: f64| x >= lo - 1e-12 && x <= hi + 1e-12;
    type Cand = (Vec<Tick>, Vec<f64>);
    let (mut decades, mut mantissas, mut linear): (Vec<Cand>, Vec<Cand>, Vec<Cand>) =
        Default::default();
    // Decades, every `stride`-th.
    if b >= a {
        let count = (b - a + 1) as usize;
        let plain = plain_range(a, b);
        for stride in 1..=count.max(1) as i32 {
            let ticks: Vec<Tick> = (a..=b)
                .filter(|d| d.rem_euclid(stride) == 0)
                .map(|d| {
                    let t = if plain {
                        fixed(10f64.powi(d), (-d).max(0) as usize)
                    } else {
                        format!("10{}", superscript(d))
                    };
                    (f64::from(d), t)
                })
                .collect();
            let mut light = Vec::new();
            if stride == 1 && count <= 8 {
                for d in (a - 1)..=b {
                    for k in 2..=9 {
                        let x = f64::from(d) + f64::from(k).log10();
                        if inside(x) {
                            light.push(x);
                        }
                    }
                }
            }
            decades.push((ticks, light));
        }
    }
    // Mantissa sets within the decades.
    for set in [&[1.0, 3.0][..], &[1.0, 2.0, 5.0][..]] {
        let mut v = Vec::new();
        for d in (lo.floor() as i32)..=(hi.ceil() as i32) {
            for &k in set {
                let x = (k * 10f64.powi(d)).log10();
                if inside(x) {
                    v.push((x, k, d));
                }
            }
        }
        if let (Some(f), Some(l)) = (v.first(), v.last()) {
            let plain = plain_range(f.2, l.2);
            let t = v
                .iter()
                .map(|&(x, k, d)| (x, value_text(k * 10f64.powi(d), plain)))
                .collect();
            mantissas.push((t, vec![]));
        }
    }
    // Round linear steps of the values (less than a decade in view).
    if hi - lo < 1.0 {
        for m in (2..=n.max(2)).rev() {
            let lin: Vec<Tick> = linear_ticks(10f64.powf(lo), 10f64.powf(hi), m)
                .into_iter()
                .filter(|t| t.0 > 0.0)
                .map(|(x, t)| (x.log10(), t))
                .collect();
            linear.push((lin, vec![]));
        }
    }
    // Decades when three or more fit, else 1-3 or 1-2-5, else round steps; within a tier
    // the most ticks (at most n), the first of equals.
    let most = |c: &[Cand]| -> Option<Cand> {
        let mut best: Option<&Cand> = None;
        for x in c {
            if x.0.len() <= n.max(1) && best.is_none_or(|b| x.0.len() > b.0.len()) {
                best = Some(x);
            }
        }
        best.cloned()
    };
    let tiers = [most(&decades), most(&mantissas), most(&linear)];
    if let Some(t) = tiers.iter().flatten().find(|t| t.0.len() >= 3) {
        return t.clone();
    }
    let mut best: Option<&Cand> = None;
    for t in tiers.iter().flatten() {
        if best.is_none_or(|b| t.0.len() > b.0.len()) {
            best = Some(t);
        }
    }
    best.cloned().unwrap_or_default()
}

/// Ticks and light lines of an axis over plot coordinates [lo, hi] whose labels (em `em`)
/// fit in `length` pixels: along the axis when `horizontal`, else stacked.
fn axis_ticks(
    lo: f64,
    hi: f64,
    log: bool,
    length: f64,
    em: f64,
    horizontal: bool,
    integer: bool,
) -> (Vec<Tick>, Vec<f64>) {
    let make = |n: usize| {
        if log {
            log_ticks(lo, hi, n)
        } else {
            let mut t = linear_ticks(lo, hi, n);
            if integer {
                // Counts: whole numbers only.
                t.retain(|x| x.0.fract() == 0.0);
                for x in &mut t {
                    x.1 = fixed(x.0, 0);
                }
            }
            let light = if t.len() >= 2 && !integer {
                let h = 0.5 * (t[1].0 - t[0].0);
                std::iter::once(t[0].0 - h)
                    .chain(t.iter().map(|x| x.0 + h))
                    .filter(|&x| x >= lo && x <= hi)
                    .collect()
            } else {
                vec![]
            };
            (t, light)
        }
    };
    let fits = |t: &[Tick]| {
        let need: f64 = if horizontal {
            t.iter().map(|x| text::width(&x.1, em) + 1.2 * em).sum()
        } else {
            t.len() as f64 * 1.8 * em
        };
        need <= length
    };
    // The most ticks (at most 10) whose labels fit; at least two if possible.
    for n in (2..=10).rev() {
        let (t, l) = make(n);
        if t.len() >= 2 && fits(&t) {
            return (t, l);
        }
    }
    // Nothing fits: every k-th tick of the sparsest set.
    let (t, l) = make(2);
    for k in 2..=t.len().max(2) {
        let thin: Vec<Tick> = t.iter().step_by(k).cloned().collect();
        if fits(&thin) || thin.len() <= 1 {
            return (thin, l);
        }
    }
    (t, l)
}

/// Grid values as ticks, thinned to every k-th so that the labels fit.
fn grid_ticks(vals: &[f64], log: bool, length: f64, em: f64, horizontal: bool) -> Vec<Tick> {
    let exps: Vec<i32> = vals
        .iter()
        .map(|&v| 10f64.powf(tr_inv(v, log)))
        .filter(|v| *v != 0.0)
        .map(|v| v.abs().log10().floor() as i32)
        .collect();
    let plain = plain_range(
        exps.iter().copied().min().unwrap_or(0),
        exps.iter().copied().max().unwrap_or(0),
    );
    let all: Vec<Tick> = vals
        .iter()
        .map(|&v| (v, value_text(tr_inv_value(v, log), plain)))
        .collect();
    for k in 1..=all.len().max(1) {
        let t: Vec<Tick> = all.iter().step_by(k).cloned().collect();
        let need: f64 = if horizontal {
            t.iter().map(|x| text::width(&x.1, em) + em).sum()
        } else {
            t.len() as f64 * 1.6 * em
        };
        if need <= length {
            return t;
        }
    }
    all.into_iter().take(1).collect()
}

fn tr_inv_value(v: f64, log: bool) -> f64 {
    if log {
        10f64.powf(v)
    } else {
        v
    }
}

fn tr_inv(v: f64, log: bool) -> f64 {
    // log10 of the value, for the exponent (0 for a zero value).
    let x = tr_inv_value(v, log).abs();
    if x > 0.0 {
        x.log10()
    } else {
        0.0
    }
}

// ---------------------------------------------------------------------------------------
// Sizes and layout.

/// Text and stroke sizes of a figure, pixels, from its width.
#[derive(Debug, Clone, Copy)]
struct Sz {
    w: f64,
    /// Ticks, legends, captions, cell labels (em).
    base: f64,
    /// Axis descriptions (em).
    label: f64,
    /// Panel titles (em).
    title: f64,
    gap: f64,
    /// Stroke and marker scale (1 at 900 px).
    k: f64,
}

impl Sz {
    fn new(width: u32) -> Sz {
        let w = f64::from(width.max(100));
        let base = (0.035 * w).ceil();
        Sz {
            w,
            base,
            label: (1.06 * base).round(),
            title: (1.12 * base).round(),
            gap: (0.45 * base).round(),
            k: w / 900.0,
        }
    }
    fn stroke(&self, w: u32) -> u32 {
        ((f64::from(w) * self.k).round() as u32).max(1)
    }
    fn marker(&self) -> i32 {
        (4.5 * self.k).round().max(2.0) as i32
    }
    fn tick(&self) -> i32 {
        (0.25 * self.base).round() as i32
    }
}

/// Height of one line of text at em `em`.
fn line_h(em: f64) -> f64 {
    1.3 * em
}

/// Height of a single text line's ink box (capitals + descenders) at em `em`.
fn ink_h(em: f64) -> f64 {
    0.97 * em
}

/// Greedy word wrap to `width` pixels at em `em`.
fn wrap(s: &str, em: f64, width: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut cur = String::new();
    for w in s.split_whitespace() {
        let cand = if cur.is_empty() {
            w.to_string()
        } else {
            format!("{cur} {w}")
        };
        if !cur.is_empty() && text::width(&cand, em) > width {
            lines.push(std::mem::take(&mut cur));
            cur = w.to_string();
        } else {
            cur = cand;
        }
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

/// A legend entry: what the series looks like and its name.
#[derive(Debug, Clone, PartialEq)]
struct Entry {
    name: String,
    color: usize,
    line: bool,
    dashed: bool,
    thin: bool,
    marker: Marker,
}

fn entries(p: &Panel) -> Vec<Entry> {
    let mut v: Vec<Entry> = p
        .vlines
        .iter()
        .map(|l| Entry {
            name: l.label.clone(),
            color: l.color,
            line: true,
            dashed: true,
            thin: true,
            marker: Marker::None,
        })
        .collect();
    v.extend(
        p.series
            .iter()
            .filter(|s| !s.name.is_empty())
            .map(|s| Entry {
                name: s.name.clone(),
                color: s.color,
                line: s.line,
                dashed: s.dashed,
                thin: s.width <= 1,
                marker: s.marker,
            }),
    );
    v
}

/// Legend entries flowed into rows at most `width` wide; a name too long for a row is
/// wrapped onto several lines.
#[derive(Debug, Clone, Default)]
struct Legend {
    entries: Vec<Entry>,
    /// Wrapped name of each entry.
    names: Vec<Vec<String>>,
    /// Rows: entry indices, width, lines.
    rows: Vec<(Vec<usize>, f64, usize)>,
}

impl Legend {
    fn new(entries: Vec<Entry>, sz: &Sz, width: f64) -> Legend {
        let text_w = (width - sample_w(sz) - 0.4 * sz.base).max(4.0 * sz.base);
        let names: Vec<Vec<String>> = entries
            .iter()
            .map(|e| {
                if text::width(&e.name, sz.base) <= text_w {
                    vec![e.name.clone()]
                } else {
                    wrap(&e.name, sz.base, text_w)
                }
            })
            .collect();
        let entry_w = |i: usize| {
            sample_w(sz)
                + 0.4 * sz.base
                + names[i]
                    .iter()
                    .map(|l| text::width(l, sz.base))
                    .fold(0.0, f64::max)
        };
        let mut rows: Vec<(Vec<usize>, f64, usize)> = Vec::new();
        let mut cur: (Vec<usize>, f64, usize) = (vec![], 0.0, 0);
        for (i, name) in names.iter().enumerate() {
            let w = entry_w(i);
            let sep = if cur.0.is_empty() { 0.0 } else { 1.2 * sz.base };
            if !cur.0.is_empty() && cur.1 + sep + w > width {
                rows.push(std::mem::take(&mut cur));
                cur = (vec![i], w, name.len());
            } else {
                cur.0.push(i);
                cur.1 += sep + w;
                cur.2 = cur.2.max(name.len());
            }
        }
        if !cur.0.is_empty() {
            rows.push(cur);
        }
        Legend {
            entries,
            names,
            rows,
        }
    }
    fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
    fn height(&self, sz: &Sz) -> f64 {
        if self.rows.is_empty() {
            0.0
        } else {
            self.rows.iter().map(|r| r.2).sum::<usize>() as f64 * line_h(sz.base) + sz.gap
        }
    }
    fn entry_w(&self, i: usize, sz: &Sz) -> f64 {
        sample_w(sz)
            + 0.4 * sz.base
            + self.names[i]
                .iter()
                .map(|l| text::width(l, sz.base))
                .fold(0.0, f64::max)
    }
}

fn sample_w(sz: &Sz) -> f64 {
    2.0 * sz.base
}

/// The plot ranges of an x–y panel in plot coordinates.
fn xy_ranges(p: &Panel) -> ((f64, f64), (f64, f64)) {
    let all: Vec<(f64, f64)> = p.series.iter().flat_map(|s| xy_points(p, s)).collect();
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
    (xr, yr)
}

fn xy_points(p: &Panel, s: &Series) -> Vec<(f64, f64)> {
    s.points
        .iter()
        .map(|&(x, y)| (tr(x, p.log_x), tr(y, p.log_y)))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect()
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

/// Everything needed to draw one panel in its box.
struct PanelLayout {
    title: Vec<String>,
    title_h: f64,
    /// Entries drawn below this panel (empty when shared or none).
    legend: Legend,
    xr: (f64, f64),
    yr: (f64, f64),
    xt: Vec<Tick>,
    yt: Vec<Tick>,
    xl: Vec<f64>,
    yl: Vec<f64>,
    /// Axis descriptions wrapped to lines; `y_top`: a y description too long to stand
    /// beside the plot, set above it.
    x_desc: Vec<String>,
    y_top: Vec<String>,
    y_desc: Vec<String>,
    y_area: f64,
    x_area: f64,
    top: f64,
    right: f64,
    /// Heat maps: colour bar (ticks in plot coordinates of the value, width of the block).
    bar: Option<(Vec<Tick>, f64)>,
    plot_h: f64,
}

/// Lays a panel out in a box `pw` wide; `plot_h`: the plot height, or None to take
/// `aspect` × the plot width.
fn layout_panel(
    kind: &PanelKind,
    shared: bool,
    pw: f64,
    plot_h: Option<f64>,
    aspect: f64,
    y_above: bool,
    sz: &Sz,
) -> PanelLayout {
    let (title_s, log_x, log_y) = match kind {
        PanelKind::Xy(p) => (&p.title, p.log_x, p.log_y),
        PanelKind::Heat(h) => (&h.title, h.log_x, h.log_y),
    };
    let title = wrap(title_s, sz.title, pw - 2.0 * sz.gap);
    let mut title_h = if title.is_empty() {
        sz.gap
    } else {
        title.len() as f64 * line_h(sz.title) + 0.5 * sz.gap
    };
    // Axes whose data are all whole numbers (counts: modes, impacts) get whole-number ticks.
    let (int_x, int_y) = match kind {
        PanelKind::Xy(p) => {
            let all = |f: fn(&(f64, f64)) -> f64| {
                let mut v = p.series.iter().flat_map(|s| s.points.iter()).peekable();
                v.peek().is_some() && v.all(|q| f(q).fract() == 0.0)
            };
            (all(|q| q.0) && p.vlines.is_empty(), all(|q| q.1))
        }
        PanelKind::Heat(_) => (false, false),
    };
    let (legend, xr, yr, grid) = match kind {
        PanelKind::Xy(p) => {
            let l = if shared || p.no_legend {
                vec![]
            } else {
                entries(p)
            };
            let (xr, yr) = xy_ranges(p);
            (l, xr, yr, None)
        }
        PanelKind::Heat(h) => {
            let xs: Vec<f64> = h.cells.iter().map(|c| tr(c.0, h.log_x)).collect();
            let ys: Vec<f64> = h.cells.iter().map(|c| tr(c.1, h.log_y)).collect();
            let (xe, ye) = (cell_edges(&xs), cell_edges(&ys));
            let xr = (
                xe.first().map_or(0.0, |c| c.1),
                xe.last().map_or(1.0, |c| c.2),
            );
            let yr = (
                ye.first().map_or(0.0, |c| c.1),
                ye.last().map_or(1.0, |c| c.2),
            );
            let gx: Vec<f64> = xe.iter().map(|c| c.0).collect();
            let gy: Vec<f64> = ye.iter().map(|c| c.0).collect();
            (vec![], xr, yr, Some((gx, gy, h)))
        }
    };
    let legend = Legend::new(legend, sz, pw - 2.0 * sz.gap);
    let tick = f64::from(sz.tick());
    let (x_s, y_s) = match kind {
        PanelKind::Xy(p) => (p.x_label.as_str(), p.y_label.as_str()),
        PanelKind::Heat(h) => (h.x_label.as_str(), h.y_label.as_str()),
    };
    let x_desc = wrap(x_s, sz.label, pw - 2.0 * sz.gap);
    let desc_h = |n: usize| {
        if n == 0 {
            0.0
        } else {
            0.6 * sz.gap + (n - 1) as f64 * line_h(sz.label) + ink_h(sz.label)
        }
    };
    let x_area = 2.0 * tick + ink_h(sz.base) + desc_h(x_desc.len()) + 0.3 * sz.gap;
    let top = 0.6 * sz.base;
    let bar_w = |ticks: &[Tick], label: bool| {
        let tw = ticks
            .iter()
            .map(|t| text::width(&t.1, sz.base))
            .fold(0.0, f64::max);
        sz.gap
            + 0.7 * sz.base
            + tick
            + 0.3 * sz.gap
            + tw
            + if label { sz.gap + ink_h(sz.label) } else { 0.0 }
            + 0.3 * sz.gap
    };
    let ticks_for = |plot_w: f64, plot_h: f64| {
        let (xt, xl, yt, yl) = match &grid {
            None => {
                let (xt, xl) = axis_ticks(xr.0, xr.1, log_x, plot_w, sz.base, true, int_x);
                let (yt, yl) = axis_ticks(yr.0, yr.1, log_y, plot_h, sz.base, false, int_y);
                (xt, xl, yt, yl)
            }
            Some((gx, gy, _)) => (
                grid_ticks(gx, log_x, plot_w, sz.base, true),
                vec![],
                grid_ticks(gy, log_y, plot_h, sz.base, false),
                vec![],
            ),
        };
        let bar = grid.as_ref().map(|(_, _, h)| {
            let (lo, hi) = (
                tr(h.value_range.0, h.log_value),
                tr(h.value_range.1, h.log_value),
            );
            let (t, _) = axis_ticks(
                lo.min(hi),
                lo.max(hi),
                h.log_value,
                plot_h,
                sz.base,
                false,
                false,
            );
            let w = bar_w(&t, !h.value_label.is_empty());
            (t, w)
        });
        (xt, xl, yt, yl, bar)
    };
    // First pass with a provisional plot size, second with the final one.
    let guess_w = 0.7 * pw;
    let guess_h = plot_h.unwrap_or(aspect * guess_w);
    // The y description may reach down beside the x tick labels.
    // The y description beside the plot when it fits on two rotated lines, else (or when
    // `y_above`) horizontal above the plot, below the title.
    let mut y_desc = wrap(y_s, sz.label, top + guess_h + 2.0 * tick + ink_h(sz.base));
    let mut y_top = Vec::new();
    if y_desc.len() > 2 || (y_above && !y_desc.is_empty()) {
        y_top = wrap(y_s, sz.label, pw - 2.0 * sz.gap);
        y_desc.clear();
        title_h += y_top.len() as f64 * line_h(sz.label);
    }
    let y_area_of = |yt: &[Tick]| {
        let tw = yt
            .iter()
            .map(|t| text::width(&t.1, sz.base))
            .fold(0.0, f64::max);
        sz.gap + desc_h(y_desc.len()) + 0.5 * sz.gap + tw + 2.0 * tick
    };
    let (_, _, yt0, _, bar0) = ticks_for(guess_w, guess_h);
    let y_area = y_area_of(&yt0);
    let bar_space = bar0.as_ref().map_or(0.0, |b| b.1);
    let mut right = 0.0f64;
    let plot_w0 = pw - y_area - bar_space - sz.gap;
    let (xt0, ..) = ticks_for(plot_w0, guess_h);
    if let Some(last) = xt0.last() {
        // Half the last x label may stick out to the right of the plot.
        let over = 0.5 * text::width(&last.1, sz.base) - (xr.1 - last.0) / (xr.1 - xr.0) * plot_w0;
        right = right.max(over);
    }
    right = (right + 0.5 * sz.gap).max(sz.gap) + bar_space;
    let plot_w = (pw - y_area - right).max(10.0);
    let plot_h = plot_h.unwrap_or(aspect * plot_w).max(10.0);
    let (xt, xl, yt, yl, bar) = ticks_for(plot_w, plot_h);
    let y_area = y_area.max(y_area_of(&yt));
    PanelLayout {
        title,
        title_h,
        legend,
        xr,
        yr,
        xt,
        yt,
        xl,
        yl,
        x_desc,
        y_top,
        y_desc,
        y_area,
        x_area,
        top,
        right,
        bar,
        plot_h,
    }
}

/// One legend for all panels: the only legend of a figure of several panels, or the distinct
/// entries of every panel when some entry appears in more than one panel and no two distinct
/// entries look alike (same colour, line and marker); empty otherwise (each panel keeps its
/// own legend).
fn shared_legend(lists: &[Vec<Entry>], panels: usize) -> Vec<Entry> {
    // A single legend in a figure of several panels speaks for all of them.
    if lists.len() == 1 && panels > 1 {
        return lists[0].clone();
    }
    if lists.len() < 2 {
        return vec![];
    }
    let mut union: Vec<Entry> = Vec::new();
    let mut repeated = false;
    for l in lists {
        for e in l {
            if union.contains(e) {
                repeated = true;
            } else {
                union.push(e.clone());
            }
        }
    }
    let look = |e: &Entry| (e.color, e.line, e.dashed, e.marker);
    let ambiguous = union
        .iter()
        .enumerate()
        .any(|(i, a)| union[i + 1..].iter().any(|b| look(a) == look(b)));
    if repeated && !ambiguous {
        union
    } else {
        vec![]
    }
}

/// The whole figure: panel boxes, shared legend, caption, height.
struct Layout {
    sz: Sz,
    height: u32,
    cols: usize,
    pw: f64,
    rows_h: Vec<f64>,
    panels: Vec<PanelLayout>,
    shared: Legend,
    caption: Vec<String>,
}

fn layout(
    size: (u32, u32),
    rows: usize,
    cols: usize,
    panels: &[PanelKind],
    caption: &str,
) -> Layout {
    let sz = Sz::new(size.0);
    let cols = cols.max(1);
    let rows = rows.max(panels.len().div_ceil(cols)).max(1);
    let pw = sz.w / cols as f64;
    // The plot aspect the caller's size asked for (its panels had ~80 px of decorations).
    let req_ph = (f64::from(size.1) - if caption.is_empty() { 0.0 } else { 34.0 }) / rows as f64;
    let mut aspect = ((req_ph - 80.0) / (pw - 80.0)).clamp(0.4, 0.85);
    // One legend below all panels when every panel with a legend shows the same entries.
    let lists: Vec<Vec<Entry>> = panels
        .iter()
        .filter_map(|k| match k {
            PanelKind::Xy(p) if !p.no_legend => Some(entries(p)),
            _ => None,
        })
        .filter(|e| !e.is_empty())
        .collect();
    let shared = shared_legend(&lists, panels.len());
    let is_shared = !shared.is_empty();
    // Every y description above its plot when one of them has to be.
    let y_above = panels.iter().any(|k| {
        !layout_panel(k, is_shared, pw, None, aspect, false, &sz)
            .y_top
            .is_empty()
    });
    let mut first: Vec<PanelLayout> = panels
        .iter()
        .map(|k| layout_panel(k, is_shared, pw, None, aspect, y_above, &sz))
        .collect();
    // Side by side, a plot narrower than 7 em is too cramped at this text size: stack
    // the panels in one column instead (taller, not wider).
    let (mut cols, mut rows, mut pw) = (cols, rows, pw);
    if cols > 1
        && first
            .iter()
            .any(|l| pw - l.y_area - l.right < 7.0 * sz.base)
    {
        cols = 1;
        rows = panels.len().max(1);
        pw = sz.w;
        aspect = aspect.min(0.6);
        first = panels
            .iter()
            .map(|k| layout_panel(k, is_shared, pw, None, aspect, y_above, &sz))
            .collect();
    }
    // Align the panels of a row: the same title block, plot height and axis block, so the
    // plots line up; legends below.
    let mut rows_h = Vec::with_capacity(rows);
    let mut panels_l: Vec<PanelLayout> = Vec::with_capacity(panels.len());
    for r in 0..rows {
        let idx: Vec<usize> = (r * cols..((r + 1) * cols).min(panels.len())).collect();
        let max =
            |f: &dyn Fn(&PanelLayout) -> f64| idx.iter().map(|&i| f(&first[i])).fold(0.0, f64::max);
        let plot_h = max(&|l| l.plot_h).ceil();
        let x_area = max(&|l| l.x_area);
        let legend = max(&|l| l.legend.height(&sz));
        let top = max(&|l| l.top);
        // The final layouts at the row's plot height: a y description can move above the
        // plot (adding lines to the title block) only now, so the row's title height is
        // taken from these, not from the first pass.
        let mut row: Vec<PanelLayout> = idx
            .iter()
            .map(|&i| {
                layout_panel(
                    &panels[i],
                    is_shared,
                    pw,
                    Some(plot_h),
                    aspect,
                    y_above,
                    &sz,
                )
            })
            .collect();
        let title_h = row
            .iter()
            .map(|l| l.title_h)
            .chain(idx.iter().map(|&i| first[i].title_h))
            .fold(0.0, f64::max);
        rows_h.push((title_h + top + plot_h + x_area + legend).ceil());
        for l in &mut row {
            l.title_h = title_h;
            l.x_area = x_area;
        }
        panels_l.extend(row);
    }
    let shared = Legend::new(shared, &sz, sz.w - 2.0 * sz.gap);
    let caption = wrap(caption, sz.base, sz.w - 2.0 * sz.gap);
    let cap_h = if caption.is_empty() {
        0.0
    } else {
        caption.len() as f64 * line_h(sz.base) + sz.gap
    };
    let height = rows_h.iter().sum::<f64>() + shared.height(&sz) + cap_h;
    Layout {
        sz,
        height: height.ceil() as u32,
        cols,
        pw,
        rows_h,
        panels: panels_l,
        shared,
        caption,
    }
}

// ---------------------------------------------------------------------------------------
// Drawing.

type DErr = String;

fn err<E: std::fmt::Debug>(e: E) -> DErr {
    format!("{e:?}")
}

type Root<'a, DB> = DrawingArea<DB, Shift>;

fn text_style(em: f64, c: RGBColor, h: HPos, v: VPos) -> TextStyle<'static> {
    ("sans-serif", em).into_font().color(&c).pos(Pos::new(h, v))
}

fn put<DB: DrawingBackend>(
    root: &Root<DB>,
    s: &str,
    style: &TextStyle,
    x: f64,
    y: f64,
) -> std::result::Result<(), DErr> {
    root.draw_text(s, style, (x.round() as i32, y.round() as i32))
        .map_err(err)
}

/// Draws legend rows with their top at `y`, centred in [x0, x0 + width].
fn draw_legend<DB: DrawingBackend>(
    root: &Root<DB>,
    lg: &Legend,
    x0: f64,
    width: f64,
    y: f64,
    sz: &Sz,
) -> std::result::Result<(), DErr> {
    let style = text_style(sz.base, BLACK, HPos::Left, VPos::Center);
    let block = lg.rows.iter().map(|r| r.1).fold(0.0, f64::max);
    let mut row_top = y;
    for (idx, _, lines) in &lg.rows {
        let mut x = x0 + 0.5 * (width - block).max(0.0);
        let yc = row_top + 0.5 * line_h(sz.base);
        for &i in idx {
            let en = &lg.entries[i];
            let c = color(en.color);
            let (a, b) = (x.round() as i32, (x + sample_w(sz)).round() as i32);
            let yi = yc.round() as i32;
            let stroke = c.stroke_width(sz.stroke(if en.thin { 1 } else { 2 }));
            if en.line {
                if en.dashed {
                    let d = (b - a) / 5;
                    for s in [0, 2, 4] {
                        root.draw(&PathElement::new(
                            vec![(a + s * d, yi), (a + (s + 1) * d, yi)],
                            stroke,
                        ))
                        .map_err(err)?;
                    }
                } else {
                    root.draw(&PathElement::new(vec![(a, yi), (b, yi)], stroke))
                        .map_err(err)?;
                }
            }
            draw_marker(root, en.marker, ((a + b) / 2, yi), c, sz)?;
            for (k, line) in lg.names[i].iter().enumerate() {
                put(
                    root,
                    line,
                    &style,
                    x + sample_w(sz) + 0.4 * sz.base,
                    yc + k as f64 * line_h(sz.base),
                )?;
            }
            x += lg.entry_w(i, sz) + 1.2 * sz.base;
        }
        row_top += *lines as f64 * line_h(sz.base);
    }
    Ok(())
}

fn draw_marker<DB: DrawingBackend>(
    root: &Root<DB>,
    m: Marker,
    q: (i32, i32),
    c: RGBColor,
    sz: &Sz,
) -> std::result::Result<(), DErr> {
    let ms = sz.marker();
    match m {
        Marker::None => Ok(()),
        Marker::Circle => root.draw(&Circle::new(q, ms, c.filled())).map_err(err),
        Marker::Square => root
            .draw(&Rectangle::new(
                [(q.0 - ms, q.1 - ms), (q.0 + ms, q.1 + ms)],
                c.filled(),
            ))
            .map_err(err),
        Marker::Triangle => root
            .draw(&TriangleMarker::new(q, ms + 1, c.filled()))
            .map_err(err),
        Marker::Cross => root
            .draw(&Cross::new(q, ms, c.stroke_width(sz.stroke(2))))
            .map_err(err),
    }
}

fn lookup(t: &[Tick], v: f64) -> String {
    t.iter()
        .find(|x| (x.0 - v).abs() <= 1e-9 * (1.0 + v.abs()))
        .map(|x| x.1.clone())
        .unwrap_or_default()
}

/// Draws one panel in the box at (x0, y0) of width `pw`.
fn draw_panel<DB: DrawingBackend>(
    root: &Root<DB>,
    kind: &PanelKind,
    l: &PanelLayout,
    (x0, y0): (f64, f64),
    pw: f64,
    sz: &Sz,
) -> std::result::Result<(), DErr> {
    let ts = text_style(sz.title, BLACK, HPos::Center, VPos::Top);
    for (i, line) in l.title.iter().enumerate() {
        put(
            root,
            line,
            &ts,
            x0 + 0.5 * pw,
            y0 + 0.2 * sz.gap + i as f64 * line_h(sz.title),
        )?;
    }
    let ls = text_style(sz.label, BLACK, HPos::Left, VPos::Top);
    for (i, line) in l.y_top.iter().enumerate() {
        let y = y0 + l.title_h - (l.y_top.len() - i) as f64 * line_h(sz.label);
        put(root, line, &ls, x0 + sz.gap, y)?;
    }
    let chart_y = y0 + l.title_h;
    let chart_h = l.top + l.plot_h + l.x_area;
    let area = root.clone().shrink(
        (x0.round() as i32, chart_y.round() as i32),
        (pw.round() as u32, chart_h.round() as u32),
    );
    let (xt, yt) = (l.xt.clone(), l.yt.clone());
    let xkeys: Vec<f64> = xt.iter().map(|t| t.0).collect();
    let ykeys: Vec<f64> = yt.iter().map(|t| t.0).collect();
    let mut chart = ChartBuilder::on(&area)
        .margin_top(l.top.round() as i32)
        .margin_right(l.right.round() as i32)
        .x_label_area_size(l.x_area.round() as i32)
        .y_label_area_size(l.y_area.round() as i32)
        .build_cartesian_2d(
            Axis {
                lo: l.xr.0,
                hi: l.xr.1,
                bold: xkeys,
                light: l.xl.clone(),
            },
            Axis {
                lo: l.yr.0,
                hi: l.yr.1,
                bold: ykeys,
                light: l.yl.clone(),
            },
        )
        .map_err(err)?;
    let xf = move |v: &f64| lookup(&xt, *v);
    let yf = move |v: &f64| lookup(&yt, *v);
    let heat = matches!(kind, PanelKind::Heat(_));
    let mut mesh = chart.configure_mesh();
    mesh.x_labels(1000)
        .y_labels(1000)
        .x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .label_style(("sans-serif", sz.base))
        .axis_desc_style(("sans-serif", sz.label))
        .set_all_tick_mark_size(sz.tick())
        .axis_style(BLACK.stroke_width(sz.stroke(1)))
        .light_line_style(RGBColor(238, 238, 238).stroke_width(sz.stroke(1)))
        .bold_line_style(RGBColor(212, 212, 212).stroke_width(sz.stroke(1)));
    if heat {
        mesh.disable_mesh();
    }
    mesh.draw().map_err(err)?;
    match kind {
        PanelKind::Xy(p) => draw_xy_series(&mut chart, p, l, sz)?,
        PanelKind::Heat(h) => draw_heat_cells(&mut chart, h, sz)?,
    }
    let (px, py) = chart.plotting_area().get_pixel_range();
    // Frame the plot.
    root.draw(&Rectangle::new(
        [(px.start, py.start), (px.end, py.end)],
        BLACK.stroke_width(sz.stroke(1)),
    ))
    .map_err(err)?;
    // Axis descriptions: x centred under the plot (kept inside the panel), y rotated and
    // centred beside it, first line leftmost.
    let tick = f64::from(sz.tick());
    let xs = text_style(sz.label, BLACK, HPos::Center, VPos::Top);
    let plot_cx = 0.5 * f64::from(px.start + px.end);
    for (i, line) in l.x_desc.iter().enumerate() {
        let hw = 0.5 * text::width(line, sz.label);
        let cx = plot_cx.min(x0 + pw - sz.gap - hw).max(x0 + sz.gap + hw);
        let y = f64::from(py.end)
            + 2.0 * tick
            + ink_h(sz.base)
            + 0.6 * sz.gap
            + i as f64 * line_h(sz.label);
        put(root, line, &xs, cx, y)?;
    }
    let ys =
        text_style(sz.label, BLACK, HPos::Center, VPos::Top).transform(FontTransform::Rotate270);
    let plot_cy = 0.5 * f64::from(py.start + py.end);
    for (i, line) in l.y_desc.iter().enumerate() {
        let hw = 0.5 * text::width(line, sz.label);
        let bottom = f64::from(py.end) + 2.0 * tick + ink_h(sz.base);
        let cy = plot_cy.min(bottom - hw).max(chart_y + hw);
        put(
            root,
            line,
            &ys,
            x0 + sz.gap + i as f64 * line_h(sz.label),
            cy,
        )?;
    }
    if let (PanelKind::Heat(h), Some((bt, _))) = (kind, &l.bar) {
        draw_bar(root, h, bt, (px.end, py.clone()), x0 + pw, sz)?;
    }
    if !l.legend.is_empty() {
        draw_legend(
            root,
            &l.legend,
            x0 + sz.gap,
            pw - 2.0 * sz.gap,
            chart_y + chart_h + 0.3 * sz.gap,
            sz,
        )?;
    }
    Ok(())
}

/// A linear axis over [lo, hi] (plot coordinates) with the ticks chosen here.
#[derive(Clone)]
struct Axis {
    lo: f64,
    hi: f64,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Ranged for Axis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;
    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = (v - self.lo) / (self.hi - self.lo);
        (f64::from(limit.0) + t * f64::from(limit.1 - limit.0)).round() as i32
    }
    fn key_points<H: plotters::coord::ranged1d::KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }
    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<Axis, Axis>>;

fn draw_xy_series<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    p: &Panel,
    l: &PanelLayout,
    sz: &Sz,
) -> std::result::Result<(), DErr> {
    let (yr0, yr1) = l.yr;
    let dash = |n: f64| (n * sz.k).round().max(1.0) as u32;
    for v in &p.vlines {
        let x = tr(v.x, p.log_x);
        if !x.is_finite() {
            continue;
        }
        let c = color(v.color);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x, yr0), (x, yr1)],
                dash(7.0),
                dash(5.0),
                c.stroke_width(sz.stroke(1)),
            ))
            .map_err(err)?;
    }
    let ms = sz.marker();
    for s in &p.series {
        let c = color(s.color);
        let data = xy_points(p, s);
        let style = c.stroke_width(sz.stroke(s.width));
        if s.line {
            if s.dashed {
                chart
                    .draw_series(DashedLineSeries::new(
                        data.clone(),
                        dash(9.0),
                        dash(6.0),
                        style,
                    ))
                    .map_err(err)?;
            } else {
                chart
                    .draw_series(LineSeries::new(data.clone(), style))
                    .map_err(err)?;
            }
        }
        match s.marker {
            Marker::None => {}
            Marker::Circle => {
                chart
                    .draw_series(data.iter().map(|&q| Circle::new(q, ms, c.filled())))
                    .map_err(err)?;
            }
            Marker::Square => {
                chart
                    .draw_series(data.iter().map(|&q| {
                        EmptyElement::at(q) + Rectangle::new([(-ms, -ms), (ms, ms)], c.filled())
                    }))
                    .map_err(err)?;
            }
            Marker::Triangle => {
                chart
                    .draw_series(
                        data.iter()
                            .map(|&q| TriangleMarker::new(q, ms + 1, c.filled())),
                    )
                    .map_err(err)?;
            }
            Marker::Cross => {
                chart
                    .draw_series(
                        data.iter()
                            .map(|&q| Cross::new(q, ms, c.stroke_width(sz.stroke(2)))),
                    )
                    .map_err(err)?;
            }
        }
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

/// Position of a value on the colour scale, 0 … 1 (unclamped).
fn scale_pos(h: &Heat, v: f64) -> f64 {
    let (lo, hi) = (
        tr(h.value_range.0, h.log_value),
        tr(h.value_range.1, h.log_value),
    );
    (tr(if h.log_value { v.max(1e-300) } else { v }, h.log_value) - lo) / (hi - lo)
}

fn draw_heat_cells<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    h: &Heat,
    sz: &Sz,
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
    // Cell labels only when every label fits its cell.
    let labels: Vec<Option<String>> = h
        .cells
        .iter()
        .map(|c| c.2.filter(|v| v.is_finite()).map(|v| value_text(v, false)))
        .collect();
    let area = chart.plotting_area();
    let (px, py) = area.get_pixel_range();
    let to_px = |x: f64, y: f64| {
        let (a, b) = area.map_coordinate(&(x, y));
        (f64::from(a), f64::from(b))
    };
    let _ = (px, py);
    let fits = h.cells.iter().enumerate().all(|(i, _)| {
        let ((xl, xh), (yl, yh)) = (span(xs[i], &xe), span(ys[i], &ye));
        let (a, b) = (to_px(xl, yl), to_px(xh, yh));
        let (w, hgt) = ((b.0 - a.0).abs(), (b.1 - a.1).abs());
        labels[i]
            .as_ref()
            .is_none_or(|t| text::width(t, sz.base) <= 0.9 * w && 1.3 * sz.base <= hgt)
    });
    for (i, c) in h.cells.iter().enumerate() {
        let ((xl, xh), (yl, yh)) = (span(xs[i], &xe), span(ys[i], &ye));
        let fill = match c.2 {
            Some(v) if v.is_finite() => ramp(scale_pos(h, v)),
            _ => RGBColor(200, 200, 200),
        };
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(xl, yl), (xh, yh)],
                fill.filled(),
            )))
            .map_err(err)?;
        match (&labels[i], c.2) {
            (Some(t), Some(v)) if fits => {
                let tc = if scale_pos(h, v) < 0.6 { WHITE } else { BLACK };
                chart
                    .draw_series(std::iter::once(Text::new(
                        t.clone(),
                        (0.5 * (xl + xh), 0.5 * (yl + yh)),
                        text_style(sz.base, tc, HPos::Center, VPos::Center),
                    )))
                    .map_err(err)?;
            }
            (None, _) => {
                // Failed (or undefined) cell: crossed out.
                let (fx, fy) = (0.25 * (xh - xl), 0.25 * (yh - yl));
                let st = RGBColor(90, 90, 90).stroke_width(sz.stroke(2));
                chart
                    .draw_series([
                        PathElement::new(vec![(xl + fx, yl + fy), (xh - fx, yh - fy)], st),
                        PathElement::new(vec![(xl + fx, yh - fy), (xh - fx, yl + fy)], st),
                    ])
                    .map_err(err)?;
            }
            _ => {}
        }
    }
    Ok(())
}

/// The colour bar of a heat map right of the plot (right edge `px_end`, vertical range `py`),
/// its label against the panel's right edge `right`.
fn draw_bar<DB: DrawingBackend>(
    root: &Root<DB>,
    h: &Heat,
    ticks: &[Tick],
    (px_end, py): (i32, std::ops::Range<i32>),
    right: f64,
    sz: &Sz,
) -> std::result::Result<(), DErr> {
    let x0 = f64::from(px_end) + sz.gap;
    let x1 = x0 + 0.7 * sz.base;
    let (top, bottom) = (f64::from(py.start), f64::from(py.end));
    let n = 96;
    for i in 0..n {
        let (a, b) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
        let (ya, yb) = (bottom - a * (bottom - top), bottom - b * (bottom - top));
        root.draw(&Rectangle::new(
            [
                (x0.round() as i32, yb.floor() as i32),
                (x1.round() as i32, ya.ceil() as i32),
            ],
            ramp(0.5 * (a + b)).filled(),
        ))
        .map_err(err)?;
    }
    root.draw(&Rectangle::new(
        [
            (x0.round() as i32, top.round() as i32),
            (x1.round() as i32, bottom.round() as i32),
        ],
        BLACK.stroke_width(sz.stroke(1)),
    ))
    .map_err(err)?;
    let (lo, hi) = (
        tr(h.value_range.0, h.log_value),
        tr(h.value_range.1, h.log_value),
    );
    let ls = text_style(sz.base, BLACK, HPos::Left, VPos::Center);
    let tick = f64::from(sz.tick());
    for (v, t) in ticks {
        let y = bottom - (v - lo) / (hi - lo) * (bottom - top);
        root.draw(&PathElement::new(
            vec![
                (x1.round() as i32, y.round() as i32),
                ((x1 + tick).round() as i32, y.round() as i32),
            ],
            BLACK.stroke_width(sz.stroke(1)),
        ))
        .map_err(err)?;
        put(root, t, &ls, x1 + tick + 0.3 * sz.gap, y)?;
    }
    if !h.value_label.is_empty() {
        let st = text_style(sz.label, BLACK, HPos::Center, VPos::Bottom)
            .transform(FontTransform::Rotate270);
        put(
            root,
            &h.value_label,
            &st,
            right - 0.3 * sz.gap,
            0.5 * (top + bottom),
        )?;
    }
    Ok(())
}

fn draw_all<DB: DrawingBackend>(
    root: &Root<DB>,
    panels: &[PanelKind],
    lay: &Layout,
) -> std::result::Result<(), DErr> {
    root.fill(&WHITE).map_err(err)?;
    let sz = &lay.sz;
    let mut y = 0.0;
    for (r, rh) in lay.rows_h.iter().enumerate() {
        for c in 0..lay.cols {
            let i = r * lay.cols + c;
            if let (Some(k), Some(l)) = (panels.get(i), lay.panels.get(i)) {
                draw_panel(root, k, l, (c as f64 * lay.pw, y), lay.pw, sz)?;
            }
        }
        y += rh;
    }
    if !lay.shared.is_empty() {
        draw_legend(root, &lay.shared, sz.gap, sz.w - 2.0 * sz.gap, y, sz)?;
        y += lay.shared.height(sz);
    }
    let cs = text_style(sz.base, RGBColor(60, 60, 60), HPos::Left, VPos::Top);
    for (i, line) in lay.caption.iter().enumerate() {
        put(
            root,
            line,
            &cs,
            sz.gap,
            y + 0.5 * sz.gap + i as f64 * line_h(sz.base),
        )?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// Draws `panels` on a `rows × cols` grid (row-major) with an optional caption at the bottom
/// and writes `<dir>/<stem>.png` and `<dir>/<stem>.svg`. `size.0` is the width in pixels;
/// `size.1` only sets the aspect ratio of the plots (see the module documentation), the
/// height follows from the layout.
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
    let lay = layout(size, rows, cols, panels, caption);
    let px = (size.0.max(100), lay.height);
    // PNG: draw into a temporary file (the extension picks the encoder), then rename.
    let png = dir.join(format!("{stem}.png"));
    let tmp = dir.join(format!(".{stem}.tmp-{}.png", std::process::id()));
    {
        let root = OutlineText::bitmap(BitMapBackend::new(&tmp, px)).into_drawing_area();
        if let Err(e) = draw_all(&root, panels, &lay) {
            drop(root);
            let _ = std::fs::remove_file(&tmp);
            return Err(fail("png", e));
        }
    }
    std::fs::rename(&tmp, &png).map_err(|e| fail("png", e.to_string()))?;
    let mut svg = String::new();
    let texts = {
        let (backend, texts) = OutlineText::svg(SVGBackend::with_string(&mut svg, px));
        let root = backend.into_drawing_area();
        draw_all(&root, panels, &lay).map_err(|e| fail("svg", e))?;
        texts
    };
    let svg = text::finish_svg(&svg, texts);
    write_atomic(&dir.join(format!("{stem}.svg")), svg.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_decades_with_readable_labels() {
        let (t, light) = log_ticks(-2.3, 1.2, 8);
        let labels: Vec<&str> = t.iter().map(|x| x.1.as_str()).collect();
        assert_eq!(labels, ["0.01", "0.1", "1", "10"]);
        assert!(light.contains(&2f64.log10()));
        let (t, _) = log_ticks(-8.5, -0.5, 8);
        assert_eq!(t.first().map(|x| x.1.as_str()), Some("10⁻⁸"));
        assert_eq!(t.last().map(|x| x.1.as_str()), Some("10⁻¹"));
        // Few labels fit: every other decade.
        let (t, _) = log_ticks(-8.5, -0.5, 4);
        assert!(t.len() <= 4 && t.iter().all(|x| x.0 as i32 % 2 == 0));
        // Less than a decade: 1-3, 1-2-5 or round steps.
        let l: Vec<String> = log_ticks(-1.82, -0.40, 3)
            .0
            .into_iter()
            .map(|x| x.1)
            .collect();
        assert_eq!(l, ["0.03", "0.1", "0.3"]);
        let l: Vec<String> = log_ticks(-1.82, -0.40, 4)
            .0
            .into_iter()
            .map(|x| x.1)
            .collect();
        assert_eq!(l, ["0.02", "0.05", "0.1", "0.2"]);
    }

    #[test]
    fn short_log_ranges_use_1_2_5() {
        let (t, _) = log_ticks(0.1f64.log10(), 0.9f64.log10(), 6);
        let labels: Vec<&str> = t.iter().map(|x| x.1.as_str()).collect();
        assert_eq!(labels, ["0.1", "0.2", "0.5"]);
    }

    #[test]
    fn linear_ticks_are_round() {
        let l: Vec<String> = linear_ticks(-0.13, 1.07, 5)
            .into_iter()
            .map(|x| x.1)
            .collect();
        assert_eq!(l, ["0", "0.25", "0.50", "0.75", "1.00"]);
        let l: Vec<String> = linear_ticks(0.0, 1.6e8, 4)
            .into_iter()
            .map(|x| x.1)
            .collect();
        assert_eq!(l, ["0", "0.5×10⁸", "1.0×10⁸", "1.5×10⁸"]);
        let l: Vec<String> = linear_ticks(-3.0, 17.0, 4)
            .into_iter()
            .map(|x| x.1)
            .collect();
        assert_eq!(l, ["0", "5", "10", "15"]);
        let l: Vec<String> = linear_ticks(-0.25, 0.25, 2)
            .into_iter()
            .map(|x| x.1)
            .collect();
        assert_eq!(l, ["−0.25", "0", "0.25"]);
    }

    #[test]
    fn degenerate_data_still_draws_both_files() {
        // A failed heat cell, an empty series, NaN and infinite points, a constant series,
        // a long unbreakable legend name: both files are written, the SVG without <text>.
        let dir = std::env::temp_dir().join(format!("pound-plot-{}", std::process::id()));
        let heat = Heat {
            title: "h".into(),
            log_x: true,
            log_y: true,
            log_value: true,
            value_range: (1e-6, 1.0),
            value_label: "err".into(),
            cells: vec![
                (1e-3, 1e8, Some(1e-3)),
                (2e-3, 1e8, None),
                (1e-3, 1e9, Some(f64::NAN)),
            ],
            ..Default::default()
        };
        let xy = Panel {
            title: "x".into(),
            x_label: "t (s)".into(),
            y_label: "u (m)".into(),
            log_y: true,
            series: vec![
                Series::line("empty", vec![], 0),
                Series::line(
                    "bad",
                    vec![(0.0, f64::NAN), (1.0, f64::INFINITY), (2.0, -1.0)],
                    1,
                ),
                Series::line(&"x".repeat(80), vec![(0.0, 2.0), (1.0, 2.0)], 2),
            ],
            ..Default::default()
        };
        figure(
            &dir,
            "t",
            (600, 400),
            (1, 2),
            &[PanelKind::Heat(heat), PanelKind::Xy(xy)],
            "c",
        )
        .unwrap();
        let svg = std::fs::read_to_string(dir.join("t.svg")).unwrap();
        assert!(!svg.contains("<text") && svg.contains("aria-label=\"err\""));
        assert!(dir.join("t.png").is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn count_axes_tick_whole_numbers() {
        let (t, light) = axis_ticks(0.9, 3.1, false, 800.0, 40.0, true, true);
        let l: Vec<&str> = t.iter().map(|x| x.1.as_str()).collect();
        assert_eq!(l, ["1", "2", "3"]);
        assert!(light.is_empty());
        // Not counts: half steps are fine.
        let (t, _) = axis_ticks(0.9, 3.1, false, 800.0, 40.0, true, false);
        assert!(t.iter().any(|x| x.1 == "1.5"));
    }

    #[test]
    fn values_read_plainly_or_with_powers_of_ten() {
        assert_eq!(value_text(5e-4, false), "5×10⁻⁴");
        assert_eq!(value_text(1e-3, false), "10⁻³");
        assert_eq!(value_text(2.5e-3, true), "0.0025");
        assert_eq!(value_text(0.01, true), "0.01");
    }
}
