//! Line plots for the speed-vs-error report: [`line_plot`] draws one or more
//! [`Series`] with markers, lines and a legend into `stem.png` (800×600) and
//! `stem.svg`, on linear or logarithmic axes.
//!
//! Text is rendered with the DejaVu Sans font embedded in the binary (the `dejavu`
//! crate), registered with plotters' `ab_glyph` text backend, so nothing depends on
//! system fonts or fontconfig. This module also holds the helpers shared with
//! [`super::picture`]: font registration, PNG and GIF encoding, error conversion.

use crate::Error;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Width of the PNG plots and pictures, px.
pub const WIDTH: u32 = 800;
/// Height of the PNG plots and pictures, px.
pub const HEIGHT: u32 = 600;

/// GIF frame delay and the delay of its last frame, 1/100 s.
const GIF_DELAY: (u16, u16) = (10, 100);
/// GIF colour quantisation speed (1 best … 30 fastest).
const GIF_SPEED: i32 = 10;

/// Font family name used for every text; DejaVu Sans is registered under it.
pub(crate) const FONT: &str = "sans-serif";

/// One named curve of a plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub label: String,
    /// `(x, y)` points, drawn in the given order.
    pub points: Vec<(f64, f64)>,
}

/// Colours of successive series (matplotlib's "tab10", cycled).
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Registers the embedded DejaVu Sans as [`FONT`] (once per process).
pub(crate) fn ensure_font() -> Result<(), Error> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok()
    });
    if ok {
        Ok(())
    } else {
        let font = Path::new("DejaVuSans.ttf (embedded)");
        Err(io_error(font, "the font could not be parsed"))
    }
}

/// An [`Error::Io`] for `path` carrying `what` (a drawing or encoding error).
pub(crate) fn io_error(path: &Path, what: impl std::fmt::Display) -> Error {
    Error::Io {
        path: path.display().to_string(),
        source: std::io::Error::other(what.to_string()),
    }
}

/// Writes an 8-bit RGB buffer of `WIDTH × HEIGHT` pixels as a PNG file.
pub(crate) fn write_png(path: &Path, rgb: &[u8]) -> Result<(), Error> {
    let file = File::create(path).map_err(|source| Error::Io {
        path: path.display().to_string(),
        source,
    })?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), WIDTH, HEIGHT);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| io_error(path, e))?;
    writer
        .write_image_data(rgb)
        .map_err(|e| io_error(path, e))?;
    writer.finish().map_err(|e| io_error(path, e))
}

/// `stem` with `extension` appended (`report/speed` → `report/speed.png`), keeping any
/// dots already in the stem.
pub(crate) fn with_suffix(stem: &Path, extension: &str) -> PathBuf {
    let mut name = stem.as_os_str().to_owned();
    name.push(".");
    name.push(extension);
    PathBuf::from(name)
}

/// An animated GIF built from the frames: written under a `.partial` name (created at
/// the first frame, so an unwritable path fails early), renamed to its real name once
/// complete, removed if never completed. The newest frame is held back so that the
/// last one can be shown longer.
pub(crate) struct GifWriter {
    path: PathBuf,
    partial: PathBuf,
    encoder: Option<gif::Encoder<BufWriter<File>>>,
    pending: Option<Vec<u8>>,
}

impl GifWriter {
    /// A writer of `path` (nothing is created before the first frame).
    pub(crate) fn new(path: PathBuf) -> Self {
        let partial = with_suffix(&path, "partial");
        Self {
            path,
            partial,
            encoder: None,
            pending: None,
        }
    }

    /// Adds a `WIDTH × HEIGHT` RGB frame.
    pub(crate) fn push(&mut self, rgb: &[u8]) -> Result<(), Error> {
        self.open()?;
        if let Some(previous) = self.pending.replace(rgb.to_vec()) {
            self.write(&previous, GIF_DELAY.0)?;
        }
        Ok(())
    }

    /// The encoder, creating the `.partial` file the first time.
    fn open(&mut self) -> Result<&mut gif::Encoder<BufWriter<File>>, Error> {
        if self.encoder.is_none() {
            let file = File::create(&self.partial).map_err(|source| Error::Io {
                path: self.partial.display().to_string(),
                source,
            })?;
            let (w, h) = (WIDTH as u16, HEIGHT as u16);
            let encoder = gif::Encoder::new(BufWriter::new(file), w, h, &[]);
            let mut encoder = encoder.map_err(|e| io_error(&self.partial, e))?;
            let repeat = encoder.set_repeat(gif::Repeat::Infinite);
            repeat.map_err(|e| io_error(&self.partial, e))?;
            self.encoder = Some(encoder);
        }
        let missing = || io_error(&self.partial, "the GIF encoder is gone");
        self.encoder.as_mut().ok_or_else(missing)
    }

    fn write(&mut self, rgb: &[u8], delay: u16) -> Result<(), Error> {
        let mut frame = gif::Frame::from_rgb_speed(WIDTH as u16, HEIGHT as u16, rgb, GIF_SPEED);
        frame.delay = delay;
        let written = self.open()?.write_frame(&frame);
        written.map_err(|e| io_error(&self.partial, e))
    }

    /// Writes the last frame, completes the file and gives it its real name.
    pub(crate) fn finish(&mut self) -> Result<(), Error> {
        if let Some(last) = self.pending.take() {
            self.write(&last, GIF_DELAY.1)?;
        }
        let Some(encoder) = self.encoder.take() else {
            return Ok(());
        };
        let partial = &self.partial;
        let mut out = encoder.into_inner().map_err(|e| io_error(partial, e))?;
        out.flush().map_err(|e| io_error(partial, e))?;
        drop(out);
        std::fs::rename(partial, &self.path).map_err(|source| Error::Io {
            path: self.path.display().to_string(),
            source,
        })
    }
}

impl Drop for GifWriter {
    /// Removes the `.partial` file of an animation that was never finished.
    fn drop(&mut self) {
        if self.encoder.take().is_some() {
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}

/// What [`line_plot`] draws, after filtering the points for the axes.
struct Plot<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    series: Vec<(&'a str, Vec<(f64, f64)>)>,
    x: Range<f64>,
    y: Range<f64>,
    log_x: bool,
    log_y: bool,
}

/// Draws `series` as lines with markers into `path_stem.png` and `path_stem.svg`, with
/// a title, axis labels and a legend; `log_x`/`log_y` make that axis logarithmic.
/// Non-finite points, and non-positive values on a logarithmic axis, are skipped (the
/// remaining points of a series are joined). An empty plot still gets its axes.
pub fn line_plot(
    path_stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_x: bool,
    log_y: bool,
) -> Result<(), Error> {
    let keep = |v: f64, log: bool| v.is_finite() && (!log || v > 0.0);
    let series: Vec<_> = series
        .iter()
        .map(|s| {
            let points = s.points.iter().copied();
            let kept = points.filter(|&(x, y)| keep(x, log_x) && keep(y, log_y));
            (s.label.as_str(), kept.collect::<Vec<_>>())
        })
        .collect();
    let all = || series.iter().flat_map(|(_, p)| p.iter().copied());
    let plot = Plot {
        title,
        x_label,
        y_label,
        x: axis_range(all().map(|p| p.0), log_x),
        y: axis_range(all().map(|p| p.1), log_y),
        series,
        log_x,
        log_y,
    };
    write_images(path_stem, &plot, true).map(drop)
}

/// A picture that can be drawn on any plotters backend.
pub(crate) trait Drawing {
    /// Draws on `area`; `raster` is true for the bitmap, false for SVG.
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        raster: bool,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>;
}

/// Draws `drawing` into `stem.png` (`WIDTH × HEIGHT`) and, if `svg`, `stem.svg`;
/// returns the PNG's RGB pixels.
pub(crate) fn write_images(
    stem: &Path,
    drawing: &impl Drawing,
    svg: bool,
) -> Result<Vec<u8>, Error> {
    ensure_font()?;
    let png_path = with_suffix(stem, "png");
    let mut rgb = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let area = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        drawing
            .draw(&area, true)
            .map_err(|e| io_error(&png_path, e))?;
        area.present().map_err(|e| io_error(&png_path, e))?;
    }
    write_png(&png_path, &rgb)?;
    if svg {
        let svg_path = with_suffix(stem, "svg");
        let area = SVGBackend::new(&svg_path, (WIDTH, HEIGHT)).into_drawing_area();
        drawing
            .draw(&area, false)
            .map_err(|e| io_error(&svg_path, e))?;
        area.present().map_err(|e| io_error(&svg_path, e))?;
    }
    Ok(rgb)
}

/// The data range of `values`: with a margin of 5 % of the span on a linear axis,
/// widened to whole decades on a logarithmic one (plotters labels decades only);
/// a default range when there are no values.
fn axis_range(values: impl Iterator<Item = f64>, log: bool) -> Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    match (lo <= hi, log) {
        (false, false) => 0.0..1.0,
        (false, true) => 1.0..10.0,
        (true, true) => {
            // A hair beyond the decades, so that rounding keeps them on the axis.
            let (lo, hi) = (lo.log10().floor(), hi.log10().ceil());
            10f64.powf(lo - 0.02)..10f64.powf(hi.max(lo + 1.0) + 0.02)
        }
        (true, false) => {
            let pad = if hi > lo {
                0.05 * (hi - lo)
            } else {
                0.5 * lo.abs().max(1.0)
            };
            lo - pad..hi + pad
        }
    }
}

impl Drawing for Plot<'_> {
    /// Picks the coordinate types for the axes' scales and draws the chart.
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        _raster: bool,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        area.fill(&WHITE)?;
        let (x, y) = (self.x.clone(), self.y.clone());
        match (self.log_x, self.log_y) {
            (false, false) => chart(area, self, x, y),
            (true, false) => chart(area, self, x.log_scale(), y),
            (false, true) => chart(area, self, x, y.log_scale()),
            (true, true) => chart(area, self, x.log_scale(), y.log_scale()),
        }
    }
}

/// Axes, mesh, series and legend on coordinates `x` × `y`.
fn chart<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    plot: &Plot<'_>,
    x: X,
    y: Y,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(plot.title, (FONT, 24))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc(plot.x_label)
        .y_desc(plot.y_label)
        .x_labels(labels(&plot.x, plot.log_x))
        .y_labels(labels(&plot.y, plot.log_y))
        .light_line_style(TRANSPARENT)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()?;
    for (i, (label, points)) in plot.series.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(
                points.iter().copied(),
                colour.stroke_width(2),
            ))?
            .label(*label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        let markers = points.iter().map(|&p| Circle::new(p, 4, colour.filled()));
        chart.draw_series(markers)?;
    }
    if !plot.series.is_empty() {
        chart
            .configure_series_labels()
            .label_font((FONT, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}

/// How many labels to ask plotters for: about 10 on a linear axis, one per decade on
/// a logarithmic one (asking for more makes plotters add light lines whose last one
/// duplicates the next decade's label).
fn labels(range: &Range<f64>, log: bool) -> usize {
    match log {
        true => 5 * ((range.end / range.start).log10().round().max(1.0) as usize),
        false => 10,
    }
}

/// A compact tick label: plain for moderate magnitudes, scientific otherwise.
fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        let s = format!("{v:.2e}");
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        format!("{mantissa}e{exponent}")
    }
}
