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

/// How a curve's line is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Dash {
    /// Continuous.
    #[default]
    Solid,
    /// Long dashes.
    Dashed,
    /// Short dashes.
    Dotted,
}

/// One curve of a plot. A point with a non-finite `y` is a gap: the line breaks there
/// instead of joining its neighbours.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
    /// Palette index of the colour (series sharing an index share a colour; the palette has
    /// ten colours and repeats).
    pub color: usize,
    /// Thin, pale line (for bounds such as ±3σ) instead of a solid one.
    pub pale: bool,
    /// Dash pattern.
    pub dash: Dash,
    /// Line width, px (0: the default, 2 for lines and 1 for bounds).
    pub width: u32,
}

impl Series {
    /// A solid curve in palette colour `color`.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>, color: usize) -> Self {
        Self {
            name: name.into(),
            points,
            color,
            pale: false,
            dash: Dash::Solid,
            width: 0,
        }
    }

    /// The same curve drawn with `dash` and `width` px.
    pub fn styled(self, dash: Dash, width: u32) -> Self {
        Self {
            dash,
            width,
            ..self
        }
    }

    /// A step curve through `points`: each value holds until the next point (for counts).
    pub fn steps(name: impl Into<String>, points: &[(f64, f64)], color: usize) -> Self {
        let mut stepped = Vec::with_capacity(2 * points.len());
        for (i, &(x, y)) in points.iter().enumerate() {
            if let Some(&(_, prev)) = i.checked_sub(1).and_then(|j| points.get(j)) {
                if prev != y && prev.is_finite() && y.is_finite() {
                    stepped.push((x, prev));
                }
            }
            stepped.push((x, y));
        }
        Self::line(name, stepped, color)
    }

    /// A pale curve (a bound) in palette colour `color`.
    pub fn bound(name: impl Into<String>, points: Vec<(f64, f64)>, color: usize) -> Self {
        Self {
            pale: true,
            ..Self::line(name, points, color)
        }
    }

    /// The runs of finite points between the gaps.
    fn segments(&self) -> impl Iterator<Item = &[(f64, f64)]> {
        self.points
            .split(|p| !(p.0.is_finite() && p.1.is_finite()))
            .filter(|run| !run.is_empty())
    }
}

/// One panel of a stacked plot. A panel whose values are all whole numbers (counts) gets
/// whole-number ticks and half a unit of margin.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Label of the y axis (with units).
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
}

impl Panel {
    /// Whether every finite value is a whole number (and there is one).
    fn counts(&self) -> bool {
        let mut values = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .filter(|v| v.is_finite())
            .peekable();
        values.peek().is_some() && values.all(|v| v.fract() == 0.0)
    }
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

/// The ten distinct colours of the Tableau 10 palette (legible on white, unlike the pale
/// entries of plotters' `Palette99`).
const PALETTE: [u32; 10] = [
    0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd, 0x8c564b, 0xe377c2, 0x7f7f7f, 0xbcbd22,
    0x17becf,
];

/// Colour `i` of the plots' ten-colour palette (Tableau 10, repeating).
pub fn palette(i: usize) -> RGBAColor {
    let [_, r, g, b] = PALETTE[i % PALETTE.len()].to_be_bytes();
    RGBColor(r, g, b).to_rgba()
}

/// Tick labels on an axis of reals (plotters' default).
const DEFAULT_TICKS: usize = 10;
/// Most tick labels on an integer axis.
const MAX_INTEGER_TICKS: usize = 16;
/// Dash length and spacing of [`Dash::Dashed`] and [`Dash::Dotted`], px.
const DASHED: (u32, u32) = (10, 6);
const DOTTED: (u32, u32) = (3, 4);
/// Relative padding of an axis range.
const RANGE_PAD: f64 = 0.05;
/// Opacity of a pale (bound) curve.
const PALE_ALPHA: f64 = 0.45;

/// An integer axis: whole numbers from `lo` to `hi` with half a unit of margin, and how many
/// labels (so that plotters puts them on whole numbers).
fn integer_range((lo, hi): (f64, f64)) -> ((f64, f64), usize) {
    let (lo, hi) = (lo.floor(), hi.ceil().max(lo.floor() + 1.0));
    let labels = ((hi - lo) as usize + 1).min(MAX_INTEGER_TICKS);
    ((lo - 0.5, hi + 0.5), labels)
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
    let pad = RANGE_PAD * (hi - lo);
    (lo - pad, hi + pad)
}

/// The extent of a panel's finite points, raw (no padding).
fn extent(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    x_label: &str,
    panel: &Panel,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let points = || panel.series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = range(points().map(|p| p.0));
    let integer_y = panel.counts();
    let ((y0, y1), y_labels) = if integer_y {
        integer_range(extent(points().map(|p| p.1)))
    } else {
        (range(points().map(|p| p.1)), DEFAULT_TICKS)
    };
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let integer = |v: &f64| format!("{v:.0}");
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_label)
        .y_desc(panel.y_label.as_str())
        .y_labels(y_labels)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16));
    if integer_y {
        mesh.y_label_formatter(&integer);
    }
    mesh.draw()?;
    for s in &panel.series {
        draw_series(&mut chart, s)?;
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

/// One curve, segment by segment (gaps stay gaps), with its legend entry.
fn draw_series<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    s: &Series,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let color = palette(s.color);
    let width = match (s.width, s.pale) {
        (0, true) => 1,
        (0, false) => 2,
        (w, _) => w,
    };
    let style = if s.pale {
        color.mix(PALE_ALPHA).stroke_width(width)
    } else {
        color.stroke_width(width)
    };
    // one legend entry per curve; an unnamed one (the second half of a ± pair) gets none
    let mut labelled = s.name.is_empty();
    let dash = s.dash;
    for seg in s.segments() {
        let pts = seg.iter().copied();
        let drawn = match dash {
            Dash::Solid => chart.draw_series(LineSeries::new(pts, style))?,
            Dash::Dashed => {
                chart.draw_series(DashedLineSeries::new(pts, DASHED.0, DASHED.1, style))?
            }
            Dash::Dotted => {
                chart.draw_series(DashedLineSeries::new(pts, DOTTED.0, DOTTED.1, style))?
            }
        };
        if !labelled {
            drawn
                .label(s.name.as_str())
                .legend(move |(x, y)| legend_glyph(x, y, dash, style));
            labelled = true;
        }
    }
    Ok(())
}

/// The legend's sample of a curve: a short stretch in its dash pattern.
fn legend_glyph(x: i32, y: i32, dash: Dash, style: ShapeStyle) -> PathElement<(i32, i32)> {
    let end = match dash {
        Dash::Solid => 20,
        Dash::Dashed => 10,
        Dash::Dotted => 4,
    };
    PathElement::new(vec![(x, y), (x + end, y)], style)
}
