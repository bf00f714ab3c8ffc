//! Charts (plotters): SVG for the report page, PNG beside it. Text is drawn with DejaVu Sans,
//! embedded (assets/), so PNG charts need no system fonts. The legend is drawn under the plot,
//! never over the data; a curves chart whose series are single points says so in its caption;
//! a y axis described as a fraction spans 0 to 1.

use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::sync::Once;

const W: u32 = 760;
/// The height of the plot (caption, axes, data); the legend's rows are added below it.
const H: u32 = 440;
/// One legend row, in pixels, and the legend's font size.
const LEGEND_ROW: u32 = 18;
const LEGEND_FONT: u32 = 13;

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            include_bytes!("../../assets/DejaVuSans.ttf"),
        );
    });
}

/// A named series of (x, y) points.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Text written beside each point (a swept knob's value), or empty.
    pub tags: Vec<String>,
}

impl Series {
    pub fn new(label: String, points: Vec<(f64, f64)>) -> Series {
        Series {
            label,
            points,
            tags: Vec::new(),
        }
    }
}

/// What kind of chart.
#[derive(Clone, Copy)]
pub enum Kind {
    /// Lines through each series' points.
    Lines,
    /// One marker per point, coloured by its series.
    Scatter,
    /// Lines through each series' points with a marker (and its tag) at each point.
    Curves,
}

/// A reference mark drawn in grey under the data, with its own legend entry: the floor of a
/// measurement.
pub enum Shape {
    /// A band from 0 up to `y`, edged by a dashed line.
    BandBelow(f64),
    /// A dashed vertical line at `x`.
    VLine(f64),
    /// A dashed line through the points.
    Dashed(Vec<(f64, f64)>),
}

pub struct Guide {
    pub label: String,
    pub shape: Shape,
}

pub struct Chart<'a> {
    pub title: &'a str,
    pub x: &'a str,
    pub y: &'a str,
    pub kind: Kind,
    pub series: &'a [Series],
    pub guides: &'a [Guide],
    /// A logarithmic x axis when the positive x values span more than 8x (points at x <= 0
    /// are then left out).
    pub log_x: bool,
}

fn color(i: usize) -> RGBColor {
    // Tableau 20: 20 distinct colours before any repeats.
    const P: [RGBColor; 20] = [
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
        RGBColor(174, 199, 232),
        RGBColor(255, 187, 120),
        RGBColor(152, 223, 138),
        RGBColor(255, 152, 150),
        RGBColor(197, 176, 213),
        RGBColor(196, 156, 148),
        RGBColor(247, 182, 210),
        RGBColor(199, 199, 199),
        RGBColor(219, 219, 141),
        RGBColor(158, 218, 229),
    ];
    P[i % P.len()]
}

/// A tick label with at most three significant digits.
fn short(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e4).contains(&a) {
        let digits = (2 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.digits$}");
        // 0.0180 -> 0.018, 1.00 -> 1 (a frame axis' ticks are whole numbers).
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{v:.1e}")
    }
}

/// Finite points of a series.
fn finite(s: &Series) -> impl Iterator<Item = (f64, f64)> + '_ {
    s.points
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
}

/// Axis ranges of the series and guides, from 0 for non-negative data; `headroom` is the
/// fraction of the y span added on top.
/// (`log`: the x values are log10s, so the x axis does not start at 0.)
fn bounds(
    series: &[Series],
    guides: &[Guide],
    headroom: f64,
    log: bool,
) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let mut xs: Vec<f64> = Vec::new();
    let mut ys: Vec<f64> = Vec::new();
    for p in series.iter().flat_map(finite) {
        xs.push(p.0);
        ys.push(p.1);
    }
    for g in guides {
        match &g.shape {
            Shape::BandBelow(y) => ys.push(*y),
            Shape::VLine(x) => xs.push(*x),
            Shape::Dashed(pts) => {
                for p in pts {
                    xs.push(p.0);
                    ys.push(p.1);
                }
            }
        }
    }
    for &x in xs.iter().filter(|v| v.is_finite()) {
        x0 = x0.min(x);
        x1 = x1.max(x);
    }
    for &y in ys.iter().filter(|v| v.is_finite()) {
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() || !y0.is_finite() {
        return ((0.0, 1.0), (0.0, 1.0));
    }
    let pad = |a: f64, b: f64, top: f64, from_zero: bool| {
        let lo = if a >= 0.0 && from_zero {
            0.0
        } else {
            a - 0.05 * (b - a)
        };
        let d = (b - lo).max(1e-9 * b.abs().max(1.0));
        (lo, b + top * d)
    };
    (pad(x0, x1, 0.08, !log), pad(y0, y1, headroom, true))
}

/// `c` with every x replaced by its log10 when it asks for a log axis and its x values span
/// more than 8x; None otherwise.
fn log_x(c: &Chart) -> Option<(Vec<Series>, Vec<Guide>)> {
    if !c.log_x {
        return None;
    }
    let xs: Vec<f64> = c
        .series
        .iter()
        .flat_map(finite)
        .map(|p| p.0)
        .filter(|&x| x > 0.0)
        .collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    if xs.is_empty() || hi < 8.0 * lo {
        return None;
    }
    let t = |x: f64| if x > 0.0 { x.log10() } else { f64::NAN };
    let series = c
        .series
        .iter()
        .map(|s| Series {
            label: s.label.clone(),
            points: s.points.iter().map(|p| (t(p.0), p.1)).collect(),
            tags: s.tags.clone(),
        })
        .collect();
    let guides = c
        .guides
        .iter()
        .map(|g| Guide {
            label: g.label.clone(),
            shape: match &g.shape {
                Shape::BandBelow(y) => Shape::BandBelow(*y),
                Shape::VLine(x) => Shape::VLine(t(*x)),
                Shape::Dashed(pts) => Shape::Dashed(pts.iter().map(|p| (t(p.0), p.1)).collect()),
            },
        })
        .collect();
    Some((series, guides))
}

/// How a legend entry is marked: a grey line (a guide) or a block of the series' colour.
enum Swatch {
    Guide,
    Block(RGBColor),
}

/// The legend under the plot: its entries (guides first, as they are drawn), in `cols`
/// columns of `col_w` pixels, filled row by row.
struct Legend {
    entries: Vec<(String, Swatch)>,
    cols: u32,
    col_w: u32,
}

impl Legend {
    fn of(c: &Chart) -> Legend {
        let mut entries: Vec<(String, Swatch)> = c
            .guides
            .iter()
            .map(|g| (g.label.clone(), Swatch::Guide))
            .collect();
        for (i, s) in c.series.iter().enumerate() {
            entries.push((s.label.clone(), Swatch::Block(color(i))));
        }
        let font = ("sans-serif", LEGEND_FONT).into_font();
        let widest = entries
            .iter()
            .map(|(label, _)| {
                font.box_size(label)
                    .map(|b| b.0)
                    .unwrap_or(8 * label.len() as u32)
            })
            .max()
            .unwrap_or(0);
        // A swatch, a gap, the text and room before the next column.
        let col_w = widest + 20 + 24;
        let cols = ((W - 24) / col_w.max(1))
            .clamp(1, 4)
            .min(entries.len().max(1) as u32);
        Legend {
            entries,
            cols,
            col_w,
        }
    }

    fn height(&self) -> u32 {
        if self.entries.is_empty() {
            return 0;
        }
        let rows = (self.entries.len() as u32).div_ceil(self.cols);
        rows * LEGEND_ROW + 12
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let e = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing a legend: {e:?}");
        let grey = RGBColor(110, 110, 110);
        let style = ("sans-serif", LEGEND_FONT)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        for (i, (label, swatch)) in self.entries.iter().enumerate() {
            let (col, row) = (i as u32 % self.cols, i as u32 / self.cols);
            let x = 16 + (col * self.col_w) as i32;
            let y = 6 + (row * LEGEND_ROW + LEGEND_ROW / 2) as i32;
            match swatch {
                Swatch::Guide => area
                    .draw(&PathElement::new(
                        [(x, y), (x + 14, y)],
                        grey.stroke_width(2),
                    ))
                    .map_err(e)?,
                Swatch::Block(col) => area
                    .draw(&Rectangle::new([(x, y - 5), (x + 14, y + 5)], col.filled()))
                    .map_err(e)?,
            }
            area.draw(&Text::new(label.clone(), (x + 20, y), style.clone()))
                .map_err(e)?;
        }
        Ok(())
    }
}

/// The caption drawn above the plot. A curves chart's parenthesis is written from its data: a
/// chart whose every series is one point (nothing swept, one VPL count) says so rather than
/// promise curves.
fn caption(c: &Chart) -> String {
    if !matches!(c.kind, Kind::Curves) {
        return c.title.to_string();
    }
    let base = c.title.split(" (").next().unwrap_or(c.title);
    if c.series.iter().all(|s| finite(s).count() <= 1) {
        format!("{base} (one point per run)")
    } else {
        format!("{base} (a curve per sampler through its swept values)")
    }
}

/// A y axis whose description says it is a fraction spans exactly 0 to 1.
fn is_fraction(c: &Chart) -> bool {
    c.y.starts_with("fraction")
}

/// Draws `c`; `log` says its x values are log10s (labelled as the values).
fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, c: &Chart, log: bool) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing a chart: {e:?}");
    root.fill(&WHITE).map_err(e)?;
    let (root, legend_area) = root.split_vertically(H);
    // The legend is under the plot, so the data need only a little room above them.
    let ((x0, x1), (mut y0, mut y1)) = bounds(c.series, c.guides, 0.05, log);
    if is_fraction(c) {
        (y0, y1) = (0.0, 1.0);
    }
    let x_label = |v: &f64| {
        if log {
            short(10f64.powf(*v))
        } else {
            short(*v)
        }
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(caption(c), ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(if log {
            format!("{} (log scale)", c.x)
        } else {
            c.x.to_string()
        })
        .y_desc(c.y)
        .x_labels(10)
        .y_labels(10)
        .x_label_formatter(&x_label)
        .y_label_formatter(&|v| short(*v))
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .draw()
        .map_err(e)?;
    // Guides first, under the data.
    let grey = RGBColor(110, 110, 110);
    for g in c.guides {
        let style = grey.stroke_width(2);
        match &g.shape {
            Shape::BandBelow(y) => {
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(x0, 0.0f64.max(y0)), (x1, *y)],
                        grey.mix(0.18).filled(),
                    )))
                    .map_err(e)?;
                chart
                    .draw_series(DashedLineSeries::new([(x0, *y), (x1, *y)], 8, 5, style))
                    .map_err(e)?
            }
            Shape::VLine(x) => chart
                .draw_series(DashedLineSeries::new([(*x, y0), (*x, y1)], 8, 5, style))
                .map_err(e)?,
            Shape::Dashed(pts) => chart
                .draw_series(DashedLineSeries::new(
                    pts.iter()
                        .copied()
                        .filter(|p| p.0.is_finite() && p.1.is_finite()),
                    8,
                    5,
                    style,
                ))
                .map_err(e)?,
        };
    }
    for (i, s) in c.series.iter().enumerate() {
        let col = color(i);
        match c.kind {
            Kind::Lines => chart
                .draw_series(LineSeries::new(finite(s), col.stroke_width(2)))
                .map_err(e)?,
            Kind::Scatter => chart
                .draw_series(finite(s).map(|p| Circle::new(p, 6, col.filled())))
                .map_err(e)?,
            Kind::Curves => {
                chart
                    .draw_series(finite(s).map(|p| Circle::new(p, 4, col.filled())))
                    .map_err(e)?;
                let tags = s
                    .points
                    .iter()
                    .zip(&s.tags)
                    .filter(|(p, _)| p.0.is_finite() && p.1.is_finite())
                    .map(|(p, t)| {
                        Text::new(
                            t.clone(),
                            *p,
                            ("sans-serif", 11).into_font().color(&col.mix(0.9)),
                        )
                    });
                chart.draw_series(tags).map_err(e)?;
                chart
                    .draw_series(LineSeries::new(finite(s), col.stroke_width(2)))
                    .map_err(e)?
            }
        };
    }
    Legend::of(c).draw(&legend_area)?;
    root.present().map_err(e)?;
    Ok(())
}

/// Draws a chart as SVG text and as an RGB PNG image.
pub fn render(c: &Chart) -> Result<(String, image::RgbImage)> {
    register_font();
    let logged = log_x(c);
    let (c, log) = match &logged {
        Some((series, guides)) => (
            &Chart {
                series,
                guides,
                log_x: false,
                ..*c
            },
            true,
        ),
        None => (c, false),
    };
    let h = H + Legend::of(c).height();
    let mut svg = String::new();
    draw(
        SVGBackend::with_string(&mut svg, (W, h)).into_drawing_area(),
        c,
        log,
    )?;
    let mut buf = vec![0u8; (W * h * 3) as usize];
    draw(
        BitMapBackend::with_buffer(&mut buf, (W, h)).into_drawing_area(),
        c,
        log,
    )?;
    let png = image::RgbImage::from_raw(W, h, buf).ok_or_else(|| anyhow!("chart buffer size"))?;
    Ok((svg, png))
}
