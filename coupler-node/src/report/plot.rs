//! Drawing with `plotters`: line charts as SVG (text is left to the viewer, so no font is
//! needed), fields as PNG images with the wet surface drawn on top.

use std::path::Path;

use plotters::prelude::*;

use crate::report::error::ReportError;

/// A named curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points in drawing order.
    pub points: Vec<(f64, f64)>,
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// The range of `values` padded by 5 % (a unit range around a constant).
fn padded(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return 0.0..1.0;
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.5 * lo.abs().max(1e-300)
    };
    (lo - pad)..(hi + pad)
}

/// Labels drawn on an axis.
pub const AXIS_LABELS: usize = 8;

/// How an axis writes its tick labels: `(v − offset) / 10^exponent` with `decimals` decimals,
/// the smallest number that tells every tick of the axis apart (no `1.020e0` repeated along an
/// axis that spans 1e-4). Values of 1e4 and above, or below 1e-2, are scaled by a power of ten
/// that is a multiple of 3 (engineering notation), written once in the axis's description; an
/// axis whose span is below 1e-4 of its values shows them less an offset, written there too.
#[derive(Clone, Debug, PartialEq)]
pub struct Ticks {
    /// The values plotters labels on the axis (its bold key points).
    pub values: Vec<f64>,
    /// Power of ten the labels are in (a multiple of 3).
    pub exponent: i32,
    /// Subtracted from each value before scaling.
    pub offset: f64,
    /// Decimals of each label.
    pub decimals: usize,
}

impl Ticks {
    /// The ticks of an axis over `range` with at most `labels` labels.
    pub fn new(range: &std::ops::Range<f64>, labels: usize) -> Ticks {
        let big = range.start.abs().max(range.end.abs());
        let span = range.end - range.start;
        let offset = if big > 0.0 && span > 0.0 && span < 1e-4 * big {
            // A round value near the middle: the span's power of ten, times 100.
            let unit = 10f64.powi(span.log10().floor() as i32 + 2);
            ((range.start + range.end) / 2.0 / unit).round() * unit
        } else {
            0.0
        };
        let shown = (range.start - offset).abs().max((range.end - offset).abs());
        let exponent = if shown > 0.0 && !(1e-2..1e4).contains(&shown) {
            3 * (shown.log10() / 3.0).floor() as i32
        } else {
            0
        };
        let mut ticks = Ticks {
            values: Vec::new(),
            exponent,
            offset,
            decimals: 0,
        };
        // plotters places its ticks on the scaled axis (it gives one tick to a span below
        // f64::EPSILON, such as mass errors of 1e-16).
        let scaled = ticks.scaled(range.start)..ticks.scaled(range.end);
        if scaled.start.is_finite() && scaled.end.is_finite() && scaled.end > scaled.start {
            use plotters::coord::ranged1d::Ranged;
            let unit = 10f64.powi(exponent);
            ticks.values = plotters::coord::types::RangedCoordf64::from(scaled)
                .key_points(labels)
                .into_iter()
                .map(|v| v * unit + offset)
                .collect();
        }
        while ticks.decimals < 15 && !ticks.distinct() {
            ticks.decimals += 1;
        }
        ticks
    }

    /// `v` on the scaled axis the labels read: `(v − offset) / 10^exponent`.
    pub fn scaled(&self, v: f64) -> f64 {
        (v - self.offset) / 10f64.powi(self.exponent)
    }

    /// The label of `v`.
    pub fn label(&self, v: f64) -> String {
        self.label_scaled(self.scaled(v))
    }

    /// The label of a value on the scaled axis.
    pub fn label_scaled(&self, scaled: f64) -> String {
        let text = format!("{scaled:.*}", self.decimals);
        // No "-0.00".
        if text
            .trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            text.trim_start_matches('-').to_string()
        } else {
            text
        }
    }

    /// What the axis's description gets: ` (× 1e3)`, ` − 1.02`, or nothing.
    pub fn suffix(&self) -> String {
        let mut s = String::new();
        if self.offset != 0.0 {
            s.push_str(&format!(" − {}", self.offset));
        }
        if self.exponent != 0 {
            s.push_str(&format!(" (× 1e{})", self.exponent));
        }
        s
    }

    fn distinct(&self) -> bool {
        let labels: Vec<String> = self.values.iter().map(|&v| self.label(v)).collect();
        // NOTE: values read from the scaled key points carry round-off (0.30000000000000004);
        // labels are compared, not values.
        labels
            .iter()
            .enumerate()
            .all(|(i, a)| labels[i + 1..].iter().all(|b| a != b))
    }
}

/// An SVG line chart of `series` into `path`.
pub fn line_chart(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
) -> Result<(), ReportError> {
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(path, (800, 500)).into_drawing_area();
        root.fill(&WHITE)?;
        let all = || series.iter().flat_map(|s| s.points.iter());
        let (xr, yr) = (padded(all().map(|p| p.0)), padded(all().map(|p| p.1)));
        let (xt, yt) = (Ticks::new(&xr, AXIS_LABELS), Ticks::new(&yr, AXIS_LABELS));
        // Drawn on the axes the labels read (scaled and less the offset).
        let on = |t: &Ticks, r: &std::ops::Range<f64>| t.scaled(r.start)..t.scaled(r.end);
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(90)
            .build_cartesian_2d(on(&xt, &xr), on(&yt, &yr))?;
        chart
            .configure_mesh()
            .x_labels(AXIS_LABELS)
            .y_labels(AXIS_LABELS)
            .x_desc(format!("{x_desc}{}", xt.suffix()))
            .y_desc(format!("{y_desc}{}", yt.suffix()))
            .x_label_formatter(&|v| xt.label_scaled(*v))
            .y_label_formatter(&|v| yt.label_scaled(*v))
            .draw()?;
        for (i, s) in series.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    s.points.iter().map(|&(x, y)| (xt.scaled(x), yt.scaled(y))),
                    color.stroke_width(2),
                ))?
                .label(s.label.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color));
        }
        if series.len() > 1 {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| ReportError::Draw {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// A cell-centred 2-D field: centres and values (cells missing from the list are drawn grey).
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// `(x, y, value)` per cell.
    pub cells: Vec<(f64, f64, f64)>,
    /// Domain corners.
    pub lower: [f64; 2],
    /// Upper corner.
    pub upper: [f64; 2],
    /// Cells per axis.
    pub n: [usize; 2],
}

/// A PNG image of `field` (viridis, its own range) with `segments` (`[x0, y0, x1, y1]`)
/// drawn in white, about `width` pixels wide; returns the range of values its colours span.
pub fn field_png(
    path: &Path,
    field: &Field,
    segments: &[[f64; 4]],
    width: u32,
) -> Result<std::ops::Range<f64>, ReportError> {
    let [nx, ny] = field.n;
    if nx == 0 || ny == 0 {
        return Err(ReportError::Draw {
            path: path.to_path_buf(),
            message: "an empty grid".into(),
        });
    }
    let px = (width as usize / nx).max(1);
    let (w, h) = ((nx * px) as u32, (ny * px) as u32);
    let range = padded(field.cells.iter().map(|c| c.2));
    let (lo, span) = (range.start, range.end - range.start);
    let colours = range.clone();
    let dx = [
        (field.upper[0] - field.lower[0]) / nx as f64,
        (field.upper[1] - field.lower[1]) / ny as f64,
    ];
    let pixel = |x: f64, y: f64| -> (i32, i32) {
        let u = (x - field.lower[0]) / dx[0] * px as f64;
        let v = (field.upper[1] - y) / dx[1] * px as f64;
        (u.round() as i32, v.round() as i32)
    };
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
        root.fill(&RGBColor(128, 128, 128))?;
        for &(x, y, v) in &field.cells {
            let i = ((x - field.lower[0]) / dx[0]).floor() as i32;
            let j = ((field.upper[1] - y) / dx[1]).floor() as i32;
            let c = ViridisRGB::get_color((v - lo) / span);
            let (p, q) = (i * px as i32, j * px as i32);
            root.draw(&Rectangle::new(
                [(p, q), (p + px as i32, q + px as i32)],
                c.filled(),
            ))?;
        }
        for s in segments {
            root.draw(&PathElement::new(
                [pixel(s[0], s[1]), pixel(s[2], s[3])],
                WHITE.stroke_width(2),
            ))?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| ReportError::Draw {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    Ok(colours)
}
