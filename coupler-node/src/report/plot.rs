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
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(90)
            .build_cartesian_2d(padded(all().map(|p| p.0)), padded(all().map(|p| p.1)))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .y_label_formatter(&|v| format!("{v:.3e}"))
            .draw()?;
        for (i, s) in series.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    s.points.iter().copied(),
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
/// drawn in white, about `width` pixels wide.
pub fn field_png(
    path: &Path,
    field: &Field,
    segments: &[[f64; 4]],
    width: u32,
) -> Result<(), ReportError> {
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
    })
}
