//! A field picture a reader can use: the PNG of a 2-D field (with the wet surface drawn on it)
//! framed in an SVG with axes in metres, a colour bar with the field's unit, and a title naming
//! the field and the time. The PNG travels inside the SVG (base64), so the SVG stands alone in
//! a browser's `<img>`, which loads nothing an SVG refers to.

use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;

use plotters::style::colors::colormaps::ViridisRGB;

use crate::record::foxglove::base64;
use crate::report::error::ReportError;
use crate::report::plot::{AXIS_LABELS, Ticks};

/// What the frame around a field's PNG says.
pub struct Frame<'a> {
    /// The title (field, unit and time).
    pub title: &'a str,
    /// The colour bar's description, `p [Pa]`.
    pub quantity: &'a str,
    /// Domain corners `[x, y]` \[m\].
    pub lower: [f64; 2],
    /// Upper corner.
    pub upper: [f64; 2],
    /// The values the colours span (low to high).
    pub colours: Range<f64>,
}

/// Height of the drawn image, or its width if wider \[px\].
const SIDE: f64 = 560.0;
const LEFT: f64 = 90.0;
const TOP: f64 = 45.0;
const BAR: f64 = 22.0;

/// Writes `svg`: the PNG at `png` framed as `frame` says.
pub fn field_svg(svg: &Path, png: &Path, frame: &Frame) -> Result<(), ReportError> {
    let fail = |message: String| ReportError::Draw {
        path: svg.to_path_buf(),
        message,
    };
    let bytes = std::fs::read(png).map_err(|e| fail(format!("reading {}: {e}", png.display())))?;
    let text = frame_svg(&base64(&bytes), frame);
    std::fs::write(svg, text).map_err(|e| fail(e.to_string()))
}

/// The SVG text around the base64 PNG `data`.
fn frame_svg(data: &str, f: &Frame) -> String {
    let (wx, wy) = (f.upper[0] - f.lower[0], f.upper[1] - f.lower[1]);
    let (w, h) = if wx >= wy {
        (SIDE, SIDE * wy / wx)
    } else {
        (SIDE * wx / wy, SIDE)
    };
    let bar_x = LEFT + w + 30.0;
    let (width, height) = (bar_x + BAR + 110.0, TOP + h + 60.0);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="13">"#
    );
    let _ = writeln!(
        s,
        r#"<rect width="100%" height="100%" fill="white"/><text x="{:.1}" y="25" text-anchor="middle" font-size="16">{}</text>"#,
        width / 2.0,
        escape(f.title)
    );
    let _ = writeln!(
        s,
        r#"<image x="{LEFT}" y="{TOP}" width="{w:.1}" height="{h:.1}" preserveAspectRatio="none" href="data:image/png;base64,{data}"/>"#
    );
    let _ = writeln!(
        s,
        r#"<rect x="{LEFT}" y="{TOP}" width="{w:.1}" height="{h:.1}" fill="none" stroke="black"/>"#
    );
    // x axis.
    let xt = Ticks::new(&(f.lower[0]..f.upper[0]), AXIS_LABELS);
    for &v in &xt.values {
        let px = LEFT + (v - f.lower[0]) / wx * w;
        let y = TOP + h;
        let _ = writeln!(
            s,
            r#"<line x1="{px:.1}" y1="{y:.1}" x2="{px:.1}" y2="{:.1}" stroke="black"/><text x="{px:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            y + 5.0,
            y + 19.0,
            xt.label(v)
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">x [m]{}</text>"#,
        LEFT + w / 2.0,
        TOP + h + 42.0,
        escape(&xt.suffix())
    );
    // y axis.
    let yt = Ticks::new(&(f.lower[1]..f.upper[1]), AXIS_LABELS);
    for &v in &yt.values {
        let py = TOP + h - (v - f.lower[1]) / wy * h;
        let _ = writeln!(
            s,
            r#"<line x1="{:.1}" y1="{py:.1}" x2="{LEFT}" y2="{py:.1}" stroke="black"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"#,
            LEFT - 5.0,
            LEFT - 8.0,
            py + 4.0,
            yt.label(v)
        );
    }
    let _ = writeln!(
        s,
        r#"<text transform="translate(22 {:.1}) rotate(-90)" text-anchor="middle">y [m]{}</text>"#,
        TOP + h / 2.0,
        escape(&yt.suffix())
    );
    colour_bar(&mut s, f, bar_x, h);
    s.push_str("</svg>\n");
    s
}

/// The colour bar beside the image: viridis from `f.colours.start` (bottom) to its end.
fn colour_bar(s: &mut String, f: &Frame, x: f64, h: f64) {
    const STEPS: usize = 64;
    let (lo, hi) = (f.colours.start, f.colours.end);
    let band = h / STEPS as f64;
    for i in 0..STEPS {
        let c = ViridisRGB::get_color((i as f64 + 0.5) / STEPS as f64);
        let y = TOP + h - (i + 1) as f64 * band;
        let _ = writeln!(
            s,
            r##"<rect x="{x:.1}" y="{y:.2}" width="{BAR}" height="{:.2}" fill="#{:02x}{:02x}{:02x}"/>"##,
            band + 0.3,
            c.0,
            c.1,
            c.2
        );
    }
    let _ = writeln!(
        s,
        r#"<rect x="{x:.1}" y="{TOP}" width="{BAR}" height="{h:.1}" fill="none" stroke="black"/>"#
    );
    if hi > lo {
        let t = Ticks::new(&(lo..hi), AXIS_LABELS);
        for &v in &t.values {
            let y = TOP + h - (v - lo) / (hi - lo) * h;
            let _ = writeln!(
                s,
                r#"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="black"/><text x="{:.1}" y="{:.1}">{}</text>"#,
                x + BAR,
                x + BAR + 5.0,
                x + BAR + 8.0,
                y + 4.0,
                t.label(v)
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{x:.1}" y="{:.1}">{}{}</text>"#,
            TOP - 8.0,
            escape(f.quantity),
            escape(&t.suffix())
        );
    }
}

/// `&`, `<`, `>` and `"` as XML entities.
pub fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
