//! PNG figures with plotters: Bode diagrams (magnitude and unwrapped phase over a log
//! frequency axis) and x-y line/point plots for the identification and diagnosis reports.

use crate::linear::unwrapped_phase;
use num_complex::Complex64;
use plotters::prelude::*;
use std::path::Path;

/// A failed figure, with the file it was meant for.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw {path}: {message}")]
pub struct PlotError {
    pub path: String,
    pub message: String,
}

/// One frequency response to draw.
pub struct BodeCurve<'a> {
    pub label: &'a str,
    pub frequency_hz: &'a [f64],
    pub response: &'a [Complex64],
}

/// One x-y series: a line, or points when `points` is set.
pub struct Series<'a> {
    pub label: &'a str,
    pub x: &'a [f64],
    pub y: &'a [f64],
    pub points: bool,
}

const SIZE: (u32, u32) = (1000, 760);

fn color(i: usize) -> RGBColor {
    const C: [RGBColor; 6] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(255, 127, 14),
        RGBColor(148, 103, 189),
        RGBColor(90, 90, 90),
    ];
    C[i % C.len()]
}

fn range(values: impl Iterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = (hi - lo).max(1e-12 * hi.abs().max(1.0));
    (lo - pad * span, hi + pad * span)
}

/// Bode diagram of `curves` between `f_lo` and `f_hi` Hz: magnitude (linear) above,
/// phase in degrees below. `magnitude_label` names the gain's unit.
pub fn bode_png(
    path: &Path,
    title: &str,
    magnitude_label: &str,
    curves: &[BodeCurve],
    f_lo: f64,
    f_hi: f64,
) -> Result<(), PlotError> {
    write_png(path, |tmp| {
        draw_bode(tmp, title, magnitude_label, curves, f_lo, f_hi)
    })
}

/// Draw through a temporary sibling renamed onto `path` ([`crate::output`]); errors name
/// `path`.
fn write_png(
    path: &Path,
    draw: impl FnOnce(&Path) -> Result<(), PlotError>,
) -> Result<(), PlotError> {
    let named = |message: String| PlotError {
        path: path.display().to_string(),
        message,
    };
    crate::output::write_via_temp(
        path,
        |tmp| draw(tmp).map_err(|e| named(e.message)),
        |e| named(e.to_string()),
    )
}

fn draw_bode(
    path: &Path,
    title: &str,
    magnitude_label: &str,
    curves: &[BodeCurve],
    f_lo: f64,
    f_hi: f64,
) -> Result<(), PlotError> {
    let err = |e: String| PlotError {
        path: path.display().to_string(),
        message: e,
    };
    let in_band = |c: &BodeCurve| -> Vec<(f64, f64, f64)> {
        let ph = unwrapped_phase(c.response);
        c.frequency_hz
            .iter()
            .zip(c.response)
            .zip(ph)
            .filter(|((f, h), _)| **f >= f_lo && **f <= f_hi && h.norm().is_finite())
            .map(|((f, h), p)| (*f, h.norm(), p.to_degrees()))
            .collect()
    };
    let data: Vec<Vec<(f64, f64, f64)>> = curves.iter().map(in_band).collect();
    let (_, mag_hi) = range(data.iter().flatten().map(|d| d.1), 0.05);
    let (ph_lo, ph_hi) = range(data.iter().flatten().map(|d| d.2), 0.05);
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let (top, bottom) = root.split_vertically(SIZE.1 / 2);
    let mut mag = ChartBuilder::on(&top)
        .caption(title, ("sans-serif", 22))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(70)
        .build_cartesian_2d((f_lo..f_hi).log_scale(), 0.0..mag_hi)
        .map_err(|e| err(e.to_string()))?;
    mag.configure_mesh()
        .y_desc(magnitude_label)
        .draw()
        .map_err(|e| err(e.to_string()))?;
    for (i, (c, d)) in curves.iter().zip(&data).enumerate() {
        let col = color(i);
        mag.draw_series(LineSeries::new(
            d.iter().map(|p| (p.0, p.1)),
            col.stroke_width(2),
        ))
        .map_err(|e| err(e.to_string()))?
        .label(c.label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
    }
    draw_legend(&mut mag).map_err(err)?;
    let phase = data
        .iter()
        .enumerate()
        .map(|(i, d)| (d.iter().map(|p| (p.0, p.2)).collect(), color(i)));
    let axes = LowerAxes {
        y_desc: "phase (deg)",
        y_label_area: 70,
    };
    lower_panel(&bottom, &axes, (f_lo, f_hi), (ph_lo, ph_hi), phase).map_err(err)?;
    root.present().map_err(|e| err(e.to_string()))
}

/// An x-y plot of `series` with axis labels.
pub fn xy_png(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), PlotError> {
    write_png(path, |tmp| draw_xy(tmp, title, x_label, y_label, series))
}

fn draw_xy(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), PlotError> {
    let err = |e: String| PlotError {
        path: path.display().to_string(),
        message: e,
    };
    let (x_lo, x_hi) = range(series.iter().flat_map(|s| s.x.iter().copied()), 0.02);
    let (y_lo, y_hi) = range(series.iter().flat_map(|s| s.y.iter().copied()), 0.05);
    let root = BitMapBackend::new(path, (1000, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)
        .map_err(|e| err(e.to_string()))?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .draw()
        .map_err(|e| err(e.to_string()))?;
    for (i, s) in series.iter().enumerate() {
        let col = color(i);
        let pts =
            s.x.iter()
                .zip(s.y)
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .map(|(a, b)| (*a, *b));
        let anno = if s.points {
            chart.draw_series(pts.map(move |p| Circle::new(p, 2, col.filled())))
        } else {
            chart.draw_series(LineSeries::new(pts, col.stroke_width(2)))
        }
        .map_err(|e| err(e.to_string()))?;
        anno.label(s.label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
    }
    draw_legend(&mut chart).map_err(err)?;
    root.present().map_err(|e| err(e.to_string()))
}

/// The series' legend of `chart`, boxed on a light background (every figure's).
fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())
}

/// The lower panel's y axis: its label and the width kept for its numbers (the upper
/// panel's, so that both share one frequency axis).
struct LowerAxes {
    y_desc: &'static str,
    y_label_area: u32,
}

/// The lower panel of a two-panel figure (the Bode phase, the gain's coherence): `lines`
/// against a log frequency axis over `(f_lo, f_hi)`, y over `y_range`.
fn lower_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    axes: &LowerAxes,
    (f_lo, f_hi): (f64, f64),
    (y_lo, y_hi): (f64, f64),
    lines: impl Iterator<Item = (Vec<(f64, f64)>, RGBColor)>,
) -> Result<(), String> {
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(axes.y_label_area)
        .build_cartesian_2d((f_lo..f_hi).log_scale(), y_lo..y_hi)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("frequency (Hz)")
        .y_desc(axes.y_desc)
        .draw()
        .map_err(|e| e.to_string())?;
    for (points, col) in lines {
        chart
            .draw_series(LineSeries::new(points, col.stroke_width(2)))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// An axis label: plain between 0.01 and 10 000, in powers of ten beyond (a gain in
/// N/(m/s^2) runs to 1e5, one in m/m to 1e-3).
fn axis_number(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if (1e-2..1e4).contains(&v.abs()) {
        format!("{v:.2}")
    } else {
        format!("{v:.2e}")
    }
}

/// A gain against frequency with its confidence band and the coherence it rests on.
pub struct GainBand<'a> {
    pub frequency_hz: &'a [f64],
    pub gain: &'a [f64],
    pub lower: &'a [f64],
    pub upper: &'a [f64],
    pub coherence: &'a [f64],
}

/// Upper limit of a band figure's gain axis, in largest gains: a band that reaches
/// infinity where the coherence vanishes would otherwise flatten the gain to nothing.
const BAND_AXIS_GAINS: f64 = 2.0;

/// The band of a model-error response estimate.
impl<'a> From<&'a crate::diagnose::model_error::ResponseEstimate> for GainBand<'a> {
    fn from(e: &'a crate::diagnose::model_error::ResponseEstimate) -> Self {
        GainBand {
            frequency_hz: &e.frequency_hz,
            gain: &e.gain,
            lower: &e.lower,
            upper: &e.upper,
            coherence: &e.coherence,
        }
    }
}

/// The gain of `band` (line) with the band shaded, over a log frequency axis, above its
/// coherence; `gain_label` names the gain's unit, `band_label` the band.
pub fn gain_band_png(
    path: &Path,
    title: &str,
    gain_label: &str,
    band_label: &str,
    band: &GainBand,
) -> Result<(), PlotError> {
    write_png(path, |tmp| {
        draw_gain_band(tmp, title, gain_label, band_label, band)
    })
}

fn draw_gain_band(
    path: &Path,
    title: &str,
    gain_label: &str,
    band_label: &str,
    band: &GainBand,
) -> Result<(), PlotError> {
    let err = |e: String| PlotError {
        path: path.display().to_string(),
        message: e,
    };
    let f = band.frequency_hz;
    let (Some(&f_lo), Some(&f_hi)) = (f.first(), f.last()) else {
        return Err(err("no frequencies".into()));
    };
    let f_hi = f_hi.max(f_lo * 1.01);
    let (_, gain_hi) = range(band.gain.iter().copied(), 0.0);
    let (_, upper_hi) = range(band.upper.iter().copied(), 0.0);
    let y_hi = 1.05 * upper_hi.min(BAND_AXIS_GAINS * gain_hi);
    // a gain of zero everywhere still gets an axis
    let y_hi = if y_hi > 0.0 { y_hi } else { 1.0 };
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let (top, bottom) = root.split_vertically(SIZE.1 * 2 / 3);
    let mut chart = ChartBuilder::on(&top)
        .caption(title, ("sans-serif", 22))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(80)
        .build_cartesian_2d((f_lo..f_hi).log_scale(), 0.0..y_hi)
        .map_err(|e| err(e.to_string()))?;
    chart
        .configure_mesh()
        .y_desc(gain_label)
        .y_label_formatter(&|v| axis_number(*v))
        .draw()
        .map_err(|e| err(e.to_string()))?;
    let clip = |v: f64| if v.is_finite() { v.min(y_hi) } else { y_hi };
    let outline: Vec<(f64, f64)> = f
        .iter()
        .zip(band.upper)
        .map(|(a, b)| (*a, clip(*b)))
        .chain(f.iter().zip(band.lower).rev().map(|(a, b)| (*a, clip(*b))))
        .collect();
    let shade = color(0).mix(0.25);
    chart
        .draw_series(std::iter::once(Polygon::new(outline, shade.filled())))
        .map_err(|e| err(e.to_string()))?
        .label(band_label)
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], shade.filled()));
    let line = color(0);
    chart
        .draw_series(LineSeries::new(
            f.iter().zip(band.gain).map(|(a, b)| (*a, clip(*b))),
            line.stroke_width(2),
        ))
        .map_err(|e| err(e.to_string()))?
        .label("gain")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], line.stroke_width(2)));
    draw_legend(&mut chart).map_err(err)?;
    let coherence: Vec<(f64, f64)> = f
        .iter()
        .zip(band.coherence)
        .map(|(a, b)| (*a, *b))
        .collect();
    let axes = LowerAxes {
        y_desc: "coherence",
        y_label_area: 80,
    };
    let lines = std::iter::once((coherence, color(5)));
    lower_panel(&bottom, &axes, (f_lo, f_hi), (0.0, 1.0), lines).map_err(err)?;
    root.present().map_err(|e| err(e.to_string()))
}
