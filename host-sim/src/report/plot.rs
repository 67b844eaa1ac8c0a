//! PNG line plots with plotters (bitmap backend, bundled DejaVu Sans font: no system fonts
//! needed).

use std::path::Path;
use std::sync::Once;

use anyhow::anyhow;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

fn ensure_font() {
    REGISTER.call_once(|| {
        // The bundled font is valid; if registration failed, text would be missing, not wrong.
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One curve of a plot.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
    /// Palette index of the colour (series sharing an index share a colour).
    pub color: usize,
    /// Thin, pale line (for bounds such as ±3σ) instead of a solid one.
    pub pale: bool,
}

impl Series {
    /// A solid curve in palette colour `color`.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>, color: usize) -> Self {
        Self {
            name: name.into(),
            points,
            color,
            pale: false,
        }
    }

    /// A pale curve (a bound) in palette colour `color`.
    pub fn bound(name: impl Into<String>, points: Vec<(f64, f64)>, color: usize) -> Self {
        Self {
            name: name.into(),
            points,
            color,
            pale: true,
        }
    }
}

/// One panel of a stacked plot.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Label of the y axis (with units).
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
}

/// A single-panel line plot.
pub fn plot_lines(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: Vec<Series>,
) -> anyhow::Result<()> {
    plot_panels(
        path,
        title,
        x_label,
        &[Panel {
            y_label: y_label.to_string(),
            series,
        }],
    )
}

/// Panels stacked vertically, sharing the x axis label; 1200 px wide, 320 px per panel.
pub fn plot_panels(
    path: &Path,
    title: &str,
    x_label: &str,
    panels: &[Panel],
) -> anyhow::Result<()> {
    ensure_font();
    let height = 60 + 320 * panels.len().max(1) as u32;
    let root = BitMapBackend::new(path, (1200, height)).into_drawing_area();
    root.fill(&WHITE)
        .map_err(|e| anyhow!("plot {}: {e}", path.display()))?;
    let root = root
        .titled(title, ("sans-serif", 24))
        .map_err(|e| anyhow!("plot {}: {e}", path.display()))?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    for (area, panel) in areas.iter().zip(panels) {
        draw_panel(area, x_label, panel).map_err(|e| anyhow!("plot {}: {e}", path.display()))?;
    }
    root.present()
        .map_err(|e| anyhow!("plot {}: {e}", path.display()))?;
    Ok(())
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-300 {
        return (lo - 0.5, hi + 0.5);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    x_label: &str,
    panel: &Panel,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let points = || panel.series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = range(points().map(|p| p.0));
    let (y0, y1) = range(points().map(|p| p.1));
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(panel.y_label.as_str())
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()?;
    for s in &panel.series {
        let color = Palette99::pick(s.color).to_rgba();
        let style = if s.pale {
            color.mix(0.45).stroke_width(1)
        } else {
            color.stroke_width(2)
        };
        let legend_style = style;
        let drawn = chart.draw_series(LineSeries::new(s.points.iter().copied(), style))?;
        // an unnamed series (the second half of a ± pair) gets no legend entry
        if !s.name.is_empty() {
            drawn
                .label(s.name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], legend_style));
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .label_font(("sans-serif", 14))
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    Ok(())
}
