//! Text drawn from the glyph outlines of the committed font (`data/fonts/DejaVuSans.ttf`),
//! so that neither the PNG nor the SVG depends on the fonts of the machine that renders it.
//!
//! [`OutlineText`] wraps a plotters backend and takes over its text:
//! - bitmaps: the outlines of the whole string are rasterised with `ab_glyph_rasterizer`
//!   (exact coverage anti-aliasing, any of the four plotters rotations);
//! - SVG: each glyph used is written once as a `<path>` in font units inside `<defs>`, and
//!   every string is a `<g>` (`aria-label` = the text) of `<use>` references under
//!   `translate(x y) rotate(a) scale(s -s)`, s = em / units-per-em. The SVG holds no `<text>`
//!   element, so it renders identically with any viewer.
//!
//! Font size: the plotters text size is the em size in pixels (DejaVu Sans: capitals are
//! 0.729 em tall). Anchors: horizontally the advance width (with kerning) is aligned left,
//! centred or right; vertically `Top` puts the top of the capitals at the anchor, `Center`
//! the middle of the capitals, `Bottom` the descender line.

use std::sync::OnceLock;

use crate::table::trimmed as num;
use ab_glyph::{Font, FontRef, GlyphId, OutlineCurve, Point};
use ab_glyph_rasterizer::Rasterizer;
use plotters_backend::text_anchor::{HPos, Pos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
    FontTransform,
};

/// The committed font (DejaVu Sans, Bitstream Vera licence, `data/fonts/`).
pub static FONT_DATA: &[u8] = include_bytes!("../../../../data/fonts/DejaVuSans.ttf");

/// Font metrics in font units.
struct Face {
    font: FontRef<'static>,
    upem: f64,
    cap: f64,
    descent: f64,
}

fn face() -> &'static Face {
    static FACE: OnceLock<Face> = OnceLock::new();
    FACE.get_or_init(|| {
        // The font is compiled in; a parse failure is a build defect, not an input error.
        let font = FontRef::try_from_slice(FONT_DATA).expect("the committed font parses");
        let upem = f64::from(font.units_per_em().unwrap_or(2048.0));
        let cap = font
            .outline(font.glyph_id('H'))
            .map(|o| {
                o.curves
                    .iter()
                    .flat_map(|c| curve_points(c).into_iter().map(|p| f64::from(p.y)))
                    .fold(0.0, f64::max)
            })
            .filter(|&c| c > 0.0)
            .unwrap_or(0.729 * upem);
        let descent = f64::from(font.descent_unscaled());
        Face {
            font,
            upem,
            cap,
            descent,
        }
    })
}

/// Units per em of the committed font.
pub fn units_per_em() -> f64 {
    face().upem
}

/// Glyphs of a string with their x offsets (font units) and the total advance.
struct Run {
    glyphs: Vec<(GlyphId, f64)>,
    advance: f64,
}

fn run(text: &str) -> Run {
    let f = &face().font;
    let mut glyphs = Vec::with_capacity(text.len());
    let mut x = 0.0;
    let mut prev: Option<GlyphId> = None;
    for c in text.chars() {
        let id = f.glyph_id(c);
        if let Some(p) = prev {
            x += f64::from(f.kern_unscaled(p, id));
        }
        glyphs.push((id, x));
        x += f64::from(f.h_advance_unscaled(id));
        prev = Some(id);
    }
    Run { glyphs, advance: x }
}

/// Advance width of `text` in pixels at em size `em`.
pub fn width(text: &str, em: f64) -> f64 {
    run(text).advance * em / face().upem
}

/// Where a string goes: baseline origin (device px), rotation, pixels per font unit.
struct Placement {
    origin: (f64, f64),
    transform: FontTransform,
    scale: f64,
}

fn rotate(t: &FontTransform, x: f64, y: f64) -> (f64, f64) {
    match t {
        FontTransform::None => (x, y),
        FontTransform::Rotate90 => (-y, x),
        FontTransform::Rotate180 => (-x, -y),
        FontTransform::Rotate270 => (y, -x),
    }
}

fn place(r: &Run, em: f64, anchor: Pos, t: FontTransform, pos: BackendCoord) -> Placement {
    let fc = face();
    let s = em / fc.upem;
    let dx = match anchor.h_pos {
        HPos::Left => 0.0,
        HPos::Center => -0.5 * r.advance * s,
        HPos::Right => -r.advance * s,
    };
    let dy = match anchor.v_pos {
        VPos::Top => fc.cap * s,
        VPos::Center => 0.5 * fc.cap * s,
        VPos::Bottom => fc.descent * s,
    };
    let (ox, oy) = rotate(&t, dx, dy);
    Placement {
        origin: (f64::from(pos.0) + ox, f64::from(pos.1) + oy),
        transform: t,
        scale: s,
    }
}

impl Placement {
    /// Device position of font-unit point (x, y) (y up).
    fn device(&self, x: f64, y: f64) -> (f64, f64) {
        let (a, b) = rotate(&self.transform, x * self.scale, -y * self.scale);
        (self.origin.0 + a, self.origin.1 + b)
    }
    fn degrees(&self) -> u32 {
        match self.transform {
            FontTransform::None => 0,
            FontTransform::Rotate90 => 90,
            FontTransform::Rotate180 => 180,
            FontTransform::Rotate270 => 270,
        }
    }
}

/// One string drawn on an SVG, replaced by outlines in [`finish_svg`].
struct Item {
    text: String,
    em: f64,
    color: BackendColor,
    anchor: Pos,
    transform: FontTransform,
    pos: BackendCoord,
}

/// A plotters backend whose text is drawn from the committed font's outlines; see the
/// module documentation. `svg = true` for an SVG backend (text replaced after drawing by
/// [`finish_svg`]), false for a bitmap backend (text rasterised directly).
pub struct OutlineText<B> {
    inner: B,
    svg: bool,
    items: std::rc::Rc<std::cell::RefCell<Vec<Item>>>,
}

/// The strings drawn on an SVG [`OutlineText`], to be applied with [`finish_svg`] once the
/// backend has written the document.
pub struct SvgText(std::rc::Rc<std::cell::RefCell<Vec<Item>>>);

const MARK_OPEN: char = '\u{E000}';
const MARK_CLOSE: char = '\u{E001}';

impl<B: DrawingBackend> OutlineText<B> {
    pub fn bitmap(inner: B) -> Self {
        OutlineText {
            inner,
            svg: false,
            items: Default::default(),
        }
    }
    pub fn svg(inner: B) -> (Self, SvgText) {
        let items: std::rc::Rc<std::cell::RefCell<Vec<Item>>> = Default::default();
        (
            OutlineText {
                inner,
                svg: true,
                items: items.clone(),
            },
            SvgText(items),
        )
    }

    fn raster(&mut self, it: &Item) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        let r = run(&it.text);
        let p = place(&r, it.em, it.anchor, it.transform.clone(), it.pos);
        let f = &face().font;
        let mut curves: Vec<OutlineCurve> = Vec::new();
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for &(id, xo) in &r.glyphs {
            let Some(o) = f.outline(id) else { continue };
            let map = |q: &Point| {
                let (a, b) = p.device(f64::from(q.x) + xo, f64::from(q.y));
                (a, b)
            };
            for c in o.curves {
                for q in curve_points(&c) {
                    let (a, b) = map(q);
                    x0 = x0.min(a);
                    y0 = y0.min(b);
                    x1 = x1.max(a);
                    y1 = y1.max(b);
                }
                curves.push(map_curve(&c, |q| {
                    let (a, b) = map(&q);
                    ab_glyph::point(a as f32, b as f32)
                }));
            }
        }
        if curves.is_empty() {
            return Ok(());
        }
        let (ox, oy) = (x0.floor(), y0.floor());
        let (w, h) = ((x1.ceil() - ox) as usize + 1, (y1.ceil() - oy) as usize + 1);
        let mut ras = Rasterizer::new(w, h);
        let sh = |q: Point| ab_glyph::point(q.x - ox as f32, q.y - oy as f32);
        for c in curves {
            match c {
                OutlineCurve::Line(a, b) => ras.draw_line(sh(a), sh(b)),
                OutlineCurve::Quad(a, b, c) => ras.draw_quad(sh(a), sh(b), sh(c)),
                OutlineCurve::Cubic(a, b, c, d) => ras.draw_cubic(sh(a), sh(b), sh(c), sh(d)),
            }
        }
        let mut px = Vec::new();
        ras.for_each_pixel_2d(|x, y, c| {
            if c > 0.0 {
                px.push((x, y, c.min(1.0)));
            }
        });
        for (x, y, c) in px {
            let color = BackendColor {
                alpha: it.color.alpha * f64::from(c),
                rgb: it.color.rgb,
            };
            self.inner
                .draw_pixel((ox as i32 + x as i32, oy as i32 + y as i32), color)?;
        }
        Ok(())
    }
}

fn curve_points(c: &OutlineCurve) -> Vec<&Point> {
    match c {
        OutlineCurve::Line(a, b) => vec![a, b],
        OutlineCurve::Quad(a, b, d) => vec![a, b, d],
        OutlineCurve::Cubic(a, b, d, e) => vec![a, b, d, e],
    }
}

fn map_curve(c: &OutlineCurve, f: impl Fn(Point) -> Point) -> OutlineCurve {
    match *c {
        OutlineCurve::Line(a, b) => OutlineCurve::Line(f(a), f(b)),
        OutlineCurve::Quad(a, b, d) => OutlineCurve::Quad(f(a), f(b), f(d)),
        OutlineCurve::Cubic(a, b, d, e) => OutlineCurve::Cubic(f(a), f(b), f(d), f(e)),
    }
}

impl<B: DrawingBackend> DrawingBackend for OutlineText<B> {
    type ErrorType = B::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }
    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.ensure_prepared()
    }
    fn present(&mut self) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.present()
    }
    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_pixel(point, color)
    }
    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_line(from, to, style)
    }
    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }
    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_path(path, style)
    }
    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_circle(center, radius, style, fill)
    }
    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.fill_polygon(vert, style)
    }
    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.blit_bitmap(pos, size, src)
    }
    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        let color = style.color();
        if color.alpha == 0.0 || text.is_empty() {
            return Ok(());
        }
        let it = Item {
            text: text.to_string(),
            em: style.size(),
            color,
            anchor: style.anchor(),
            transform: style.transform(),
            pos,
        };
        if self.svg {
            let i = {
                let mut v = self.items.borrow_mut();
                v.push(it);
                v.len() - 1
            };
            // A placeholder `<text>` keeps the drawing order; `finish_svg` replaces it.
            self.inner
                .draw_text(&format!("{MARK_OPEN}{i}{MARK_CLOSE}"), style, pos)
        } else {
            self.raster(&it)
        }
    }
    fn estimate_text_size<S: BackendTextStyle>(
        &self,
        text: &str,
        style: &S,
    ) -> Result<(u32, u32), DrawingErrorKind<B::ErrorType>> {
        let em = style.size();
        Ok((width(text, em).ceil() as u32, em.ceil() as u32))
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn glyph_path(id: GlyphId) -> Option<String> {
    let o = face().font.outline(id)?;
    let mut d = String::new();
    let mut cur: Option<Point> = None;
    let mut start: Option<Point> = None;
    // A line back to the contour's start is left to the `Z` that closes it.
    let mut pending: Option<Point> = None;
    let p = |q: &Point| format!("{} {}", num(f64::from(q.x), 1), num(f64::from(q.y), 1));
    for c in &o.curves {
        let first = *curve_points(c)[0];
        if cur != Some(first) {
            if cur.is_some() {
                d.push('Z');
            }
            d.push_str(&format!("M{}", p(&first)));
            start = Some(first);
            pending = None;
        } else if let Some(q) = pending.take() {
            d.push_str(&format!("L{}", p(&q)));
        }
        match c {
            OutlineCurve::Line(_, b) => {
                if Some(*b) == start {
                    pending = Some(*b);
                } else {
                    d.push_str(&format!("L{}", p(b)));
                }
                cur = Some(*b);
            }
            OutlineCurve::Quad(_, b, e) => {
                d.push_str(&format!("Q{} {}", p(b), p(e)));
                cur = Some(*e);
            }
            OutlineCurve::Cubic(_, b, e, g) => {
                d.push_str(&format!("C{} {} {}", p(b), p(e), p(g)));
                cur = Some(*g);
            }
        }
    }
    if cur.is_some() {
        d.push('Z');
    }
    Some(d)
}

/// Replaces the placeholder `<text>` elements of `svg` (written through an SVG
/// [`OutlineText`]) by glyph outlines and adds the glyph definitions.
pub fn finish_svg(svg: &str, text: SvgText) -> String {
    let items = text.0.borrow();
    let mut used: std::collections::BTreeMap<u16, Option<String>> = Default::default();
    let mut out = String::with_capacity(svg.len());
    let mut rest = svg;
    while let Some(start) = rest.find("<text") {
        let Some(end_rel) = rest[start..].find("</text>") else {
            break;
        };
        let end = start + end_rel + "</text>".len();
        let element = &rest[start..end];
        let idx = element
            .find(MARK_OPEN)
            .and_then(|a| {
                let b = element[a..].find(MARK_CLOSE)? + a;
                element[a + MARK_OPEN.len_utf8()..b].parse::<usize>().ok()
            })
            .and_then(|i| items.get(i));
        out.push_str(&rest[..start]);
        if let Some(it) = idx {
            let r = run(&it.text);
            let pl = place(&r, it.em, it.anchor, it.transform.clone(), it.pos);
            let (r8, g8, b8) = it.color.rgb;
            out.push_str(&format!(
                "<g aria-label=\"{}\" fill=\"#{r8:02x}{g8:02x}{b8:02x}\"",
                escape(&it.text)
            ));
            if it.color.alpha < 1.0 {
                out.push_str(&format!(" fill-opacity=\"{}\"", num(it.color.alpha, 3)));
            }
            out.push_str(&format!(
                " transform=\"translate({} {})",
                num(pl.origin.0, 2),
                num(pl.origin.1, 2)
            ));
            if pl.degrees() != 0 {
                out.push_str(&format!(" rotate({})", pl.degrees()));
            }
            out.push_str(&format!(
                " scale({} {})\">",
                num(pl.scale, 7),
                num(-pl.scale, 7)
            ));
            for &(id, xo) in &r.glyphs {
                let path = used.entry(id.0).or_insert_with(|| glyph_path(id));
                if path.is_some() {
                    out.push_str(&format!("<use href=\"#g{}\" x=\"{}\"/>", id.0, num(xo, 1)));
                }
            }
            out.push_str("</g>");
        }
        rest = &rest[end..];
    }
    out.push_str(rest);
    let mut defs = String::from("<defs>");
    for (id, d) in &used {
        if let Some(d) = d {
            defs.push_str(&format!("<path id=\"g{id}\" d=\"{d}\"/>"));
        }
    }
    defs.push_str("</defs>");
    // After the opening <svg …> tag.
    if let Some(svg_at) = out.find("<svg") {
        if let Some(gt) = out[svg_at..].find('>') {
            let at = svg_at + gt + 1;
            out.insert_str(at, &defs);
        }
    }
    out
}
