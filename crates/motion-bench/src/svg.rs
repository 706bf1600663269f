//! Small hand-written SVG charts: latency histograms with overlaid series on log scales
//! (`bench --plot`) and stacked time-series panels (`motionctl record --plot`).
//!
//! Plain SVG 1.1 text, no dependency: the few shapes these two pictures need (axes, ticks,
//! labels, bars, polylines, dashed markers, a legend) are fewer lines than a plotting
//! crate's configuration, and cost nothing to compile.

use std::fmt::Write as _;

/// Colours of the series, in order: ours, then baselines.
pub const PALETTE: [&str; 6] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
];

const WIDTH: f64 = 900.0;
const MARGIN_LEFT: f64 = 80.0;
const MARGIN_RIGHT: f64 = 20.0;
const PLOT_WIDTH: f64 = WIDTH - MARGIN_LEFT - MARGIN_RIGHT;

/// Escapes text for SVG and HTML content and attributes.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A scale from data to pixels, linear or base-10 logarithmic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    low: f64,
    high: f64,
    log: bool,
    from_px: f64,
    to_px: f64,
}

impl Scale {
    /// `low..high` onto `from_px..to_px`; a log scale needs `0 < low < high`.
    pub fn new(low: f64, high: f64, log: bool, from_px: f64, to_px: f64) -> Self {
        let (mut low, mut high) = if log {
            (low.max(f64::MIN_POSITIVE), high.max(f64::MIN_POSITIVE))
        } else {
            (low, high)
        };
        if high <= low || !low.is_finite() || !high.is_finite() {
            // One value, or nothing usable: a unit-wide range around it.
            let centre = if low.is_finite() { low } else { 0.0 };
            (low, high) = if log {
                (centre.max(1.0) / 10.0, centre.max(1.0) * 10.0)
            } else {
                (centre - 1.0, centre + 1.0)
            };
        }
        Self {
            low,
            high,
            log,
            from_px,
            to_px,
        }
    }

    fn unit(&self, value: f64) -> f64 {
        if self.log {
            let value = value.max(self.low);
            (value.log10() - self.low.log10()) / (self.high.log10() - self.low.log10())
        } else {
            (value - self.low) / (self.high - self.low)
        }
    }

    /// The pixel of `value`.
    pub fn px(&self, value: f64) -> f64 {
        self.from_px + self.unit(value) * (self.to_px - self.from_px)
    }

    /// Tick positions: the powers of ten (log), or about `count` round numbers (linear).
    pub fn ticks(&self, count: usize) -> Vec<f64> {
        if self.log {
            let first = self.low.log10().ceil() as i32;
            let last = self.high.log10().floor() as i32;
            return (first..=last).map(|e| 10f64.powi(e)).collect();
        }
        let raw = (self.high - self.low) / count.max(1) as f64;
        let magnitude = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 2.5, 5.0, 10.0]
            .iter()
            .map(|m| m * magnitude)
            .find(|step| *step >= raw)
            .unwrap_or(magnitude * 10.0);
        let mut tick = (self.low / step).ceil() * step;
        let mut ticks = Vec::new();
        while tick <= self.high + step * 1e-9 && ticks.len() < 50 {
            ticks.push(if tick.abs() < step * 1e-9 { 0.0 } else { tick });
            tick += step;
        }
        ticks
    }
}

/// A number as a tick label: short, no trailing zeros.
pub fn short_number(value: f64) -> String {
    let magnitude = value.abs();
    if magnitude != 0.0 && !(1e-3..1e6).contains(&magnitude) {
        return format!("{value:.0e}");
    }
    let text = format!("{value:.3}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".to_owned()
    } else {
        text.to_owned()
    }
}

/// The SVG's opening: size, white background, font.
fn open(out: &mut String, height: f64, title: &str) {
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" viewBox="0 0 {WIDTH} {height}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(out, "<title>{}</title>", escape(title));
    let _ = writeln!(
        out,
        r#"<rect x="0" y="0" width="{WIDTH}" height="{height}" fill="white"/>"#
    );
}

/// Axes, ticks and labels of one plot area.
fn frame(
    out: &mut String,
    x: &Scale,
    y: &Scale,
    (top, bottom): (f64, f64),
    x_label: &str,
    y_label: &str,
    x_format: &dyn Fn(f64) -> String,
) {
    let _ = writeln!(
        out,
        r##"<rect x="{MARGIN_LEFT}" y="{top}" width="{PLOT_WIDTH}" height="{}" fill="none" stroke="#444"/>"##,
        bottom - top
    );
    for tick in x.ticks(8) {
        let px = x.px(tick);
        let _ = writeln!(
            out,
            r##"<line x1="{px:.1}" y1="{top}" x2="{px:.1}" y2="{bottom}" stroke="#ddd"/><text x="{px:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            bottom + 14.0,
            escape(&x_format(tick))
        );
    }
    for tick in y.ticks(5) {
        let py = y.px(tick);
        let _ = writeln!(
            out,
            r##"<line x1="{MARGIN_LEFT}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            MARGIN_LEFT + PLOT_WIDTH,
            MARGIN_LEFT - 6.0,
            py + 4.0,
            escape(&short_number(tick))
        );
    }
    let _ = writeln!(
        out,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
        MARGIN_LEFT + PLOT_WIDTH / 2.0,
        bottom + 30.0,
        escape(x_label)
    );
    let middle = (top + bottom) / 2.0;
    let _ = writeln!(
        out,
        r#"<text x="16" y="{middle:.1}" text-anchor="middle" transform="rotate(-90 16 {middle:.1})">{}</text>"#,
        escape(y_label)
    );
}

/// One bin of a histogram: `(low, high, count)`.
pub type Bin = (f64, f64, u64);

/// One series of a histogram: its bins and its percentile markers.
#[derive(Debug, Clone, PartialEq)]
pub struct HistogramSeries {
    /// The legend's text.
    pub label: String,
    /// `(low, high, count)` per bin, ascending, non-overlapping.
    pub bins: Vec<Bin>,
    /// `(name, value)` lines to mark, e.g. `("p99", 1234.0)`.
    pub markers: Vec<(String, f64)>,
}

/// A histogram picture: series overlaid (the first filled, the others outlined), log counts.
#[derive(Clone, Copy)]
pub struct HistogramChart<'a> {
    /// The heading.
    pub title: &'a str,
    /// Caption lines under the plot (machine, command).
    pub caption: &'a [String],
    /// The x axis's label.
    pub x_label: &'a str,
    /// Whether the x axis is logarithmic.
    pub log_x: bool,
    /// Tick labels of the x axis.
    pub x_format: &'a dyn Fn(f64) -> String,
    /// The series, ours first.
    pub series: &'a [HistogramSeries],
}

impl core::fmt::Debug for HistogramChart<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("HistogramChart")
            .field("title", &self.title)
            .field("series", &self.series.len())
            .finish_non_exhaustive()
    }
}

/// The histogram as an SVG document.
pub fn histogram(chart: &HistogramChart<'_>) -> String {
    let legend_top = 40.0;
    let top = legend_top + 18.0 * chart.series.len() as f64 + 10.0;
    let bottom = top + 320.0;
    let height = bottom + 50.0 + 16.0 * chart.caption.len() as f64;
    let bins = chart.series.iter().flat_map(|s| s.bins.iter());
    let x_low = bins.clone().map(|b| b.0).fold(f64::INFINITY, f64::min);
    let x_high = bins.clone().map(|b| b.1).fold(f64::NEG_INFINITY, f64::max);
    let max_count = bins.map(|b| b.2).max().unwrap_or(1).max(1) as f64;
    let x = Scale::new(
        x_low,
        x_high,
        chart.log_x,
        MARGIN_LEFT,
        MARGIN_LEFT + PLOT_WIDTH,
    );
    let y = Scale::new(0.5, max_count * 2.0, true, bottom, top);
    let mut out = String::new();
    open(&mut out, height, chart.title);
    let _ = writeln!(
        out,
        r#"<text x="{MARGIN_LEFT}" y="22" font-size="15" font-weight="bold">{}</text>"#,
        escape(chart.title)
    );
    frame(
        &mut out,
        &x,
        &y,
        (top, bottom),
        chart.x_label,
        "count (log)",
        chart.x_format,
    );
    for (index, series) in chart.series.iter().enumerate() {
        let colour = PALETTE[index % PALETTE.len()];
        if index == 0 {
            for &(low, high, count) in series.bins.iter().filter(|b| b.2 > 0) {
                let (left, right) = (x.px(low), x.px(high));
                let py = y.px(count as f64);
                let _ = writeln!(
                    out,
                    r#"<rect x="{left:.1}" y="{py:.1}" width="{:.1}" height="{:.1}" fill="{colour}" fill-opacity="0.55"/>"#,
                    (right - left).max(0.8),
                    bottom - py
                );
            }
        } else {
            let mut points = String::new();
            for &(low, high, count) in &series.bins {
                let py = if count == 0 {
                    bottom
                } else {
                    y.px(count as f64)
                };
                let _ = write!(
                    points,
                    "{:.1},{py:.1} {:.1},{py:.1} ",
                    x.px(low),
                    x.px(high)
                );
            }
            let _ = writeln!(
                out,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.8"/>"#,
                points.trim_end()
            );
        }
        for (slot, (name, value)) in series.markers.iter().enumerate() {
            let px = x.px(*value);
            let label_y = top + 12.0 + 12.0 * (index * series.markers.len() + slot) as f64;
            // Labels right of their line, or left of it near the right edge.
            let (label_x, anchor) = if px > MARGIN_LEFT + 0.75 * PLOT_WIDTH {
                (px - 3.0, "end")
            } else {
                (px + 3.0, "start")
            };
            let _ = writeln!(
                out,
                r#"<line x1="{px:.1}" y1="{top}" x2="{px:.1}" y2="{bottom}" stroke="{colour}" stroke-dasharray="4 3"/><text x="{label_x:.1}" y="{label_y:.1}" fill="{colour}" text-anchor="{anchor}">{}</text>"#,
                escape(name)
            );
        }
        let ly = legend_top + 18.0 * index as f64;
        let _ = writeln!(
            out,
            r#"<rect x="{MARGIN_LEFT}" y="{:.1}" width="14" height="10" fill="{colour}"/><text x="{:.1}" y="{ly:.1}">{}</text>"#,
            ly - 9.0,
            MARGIN_LEFT + 20.0,
            escape(&series.label)
        );
    }
    caption(&mut out, chart.caption, bottom + 50.0);
    out.push_str("</svg>\n");
    out
}

fn caption(out: &mut String, lines: &[String], first_y: f64) {
    for (index, line) in lines.iter().enumerate() {
        let _ = writeln!(
            out,
            r##"<text x="{MARGIN_LEFT}" y="{:.1}" fill="#555" font-size="11">{}</text>"##,
            first_y + 16.0 * index as f64,
            escape(line)
        );
    }
}

/// One line of a time-series panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// The legend's text.
    pub label: String,
    /// `(x, y)` points, in x order.
    pub points: Vec<(f64, f64)>,
    /// Dashed (desired values) or solid (measured).
    pub dashed: bool,
}

/// One panel of stacked time series.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// The panel's heading.
    pub title: String,
    /// The y axis's label.
    pub y_label: String,
    /// The lines.
    pub lines: Vec<Line>,
}

/// Panels stacked on one x axis (seconds), one SVG document.
pub fn time_series(title: &str, caption_lines: &[String], panels: &[Panel]) -> String {
    const PANEL_HEIGHT: f64 = 180.0;
    const GAP: f64 = 70.0;
    let x_low = panels
        .iter()
        .flat_map(|p| p.lines.iter().flat_map(|l| l.points.first()))
        .map(|p| p.0)
        .fold(f64::INFINITY, f64::min);
    let x_high = panels
        .iter()
        .flat_map(|p| p.lines.iter().flat_map(|l| l.points.last()))
        .map(|p| p.0)
        .fold(f64::NEG_INFINITY, f64::max);
    let x = Scale::new(x_low, x_high, false, MARGIN_LEFT, MARGIN_LEFT + PLOT_WIDTH);
    let first_top = 50.0;
    let bottom_last = first_top + (PANEL_HEIGHT + GAP) * panels.len() as f64;
    let height = bottom_last + 20.0 + 16.0 * caption_lines.len() as f64;
    let mut out = String::new();
    open(&mut out, height, title);
    let _ = writeln!(
        out,
        r#"<text x="{MARGIN_LEFT}" y="22" font-size="15" font-weight="bold">{}</text>"#,
        escape(title)
    );
    for (index, panel) in panels.iter().enumerate() {
        let top = first_top + (PANEL_HEIGHT + GAP) * index as f64;
        let bottom = top + PANEL_HEIGHT;
        let values = panel
            .lines
            .iter()
            .flat_map(|l| l.points.iter().map(|p| p.1));
        let low = values.clone().fold(f64::INFINITY, f64::min);
        let high = values.fold(f64::NEG_INFINITY, f64::max);
        // A constant line gets a range of ±1 (or ±5 %) around it, not ±1e-9.
        let pad = if high - low > 1e-9 {
            (high - low) * 0.05
        } else {
            (high.abs() * 0.05).max(1.0)
        };
        let y = Scale::new(low - pad, high + pad, false, bottom, top);
        let _ = writeln!(
            out,
            r#"<text x="{MARGIN_LEFT}" y="{:.1}" font-weight="bold">{}</text>"#,
            top - 8.0,
            escape(&panel.title)
        );
        frame(
            &mut out,
            &x,
            &y,
            (top, bottom),
            "time (s)",
            &panel.y_label,
            &short_number,
        );
        let mut legend_x = MARGIN_LEFT + 260.0;
        for (slot, line) in panel.lines.iter().enumerate() {
            let colour = PALETTE[slot % PALETTE.len()];
            let mut points = String::new();
            for &(px, py) in &line.points {
                let _ = write!(points, "{:.1},{:.1} ", x.px(px), y.px(py));
            }
            let dash = if line.dashed {
                r#" stroke-dasharray="6 4""#
            } else {
                ""
            };
            let _ = writeln!(
                out,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"{dash}/>"#,
                points.trim_end()
            );
            let _ = writeln!(
                out,
                r#"<line x1="{legend_x:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{colour}" stroke-width="2"{dash}/><text x="{:.1}" y="{:.1}">{}</text>"#,
                top - 12.0,
                legend_x + 24.0,
                top - 12.0,
                legend_x + 28.0,
                top - 8.0,
                escape(&line.label)
            );
            legend_x += 40.0 + 7.0 * line.label.chars().count() as f64;
        }
    }
    caption(&mut out, caption_lines, bottom_last);
    out.push_str("</svg>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_the_decades_inside() {
        let scale = Scale::new(50.0, 20_000.0, true, 0.0, 100.0);
        assert_eq!(scale.ticks(5), vec![100.0, 1000.0, 10_000.0]);
        assert!((scale.px(50.0) - 0.0).abs() < 1e-9);
        assert!((scale.px(20_000.0) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn linear_ticks_are_round_numbers() {
        let scale = Scale::new(0.0, 10.0, false, 0.0, 100.0);
        assert_eq!(scale.ticks(5), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert!((scale.px(5.0) - 50.0).abs() < 1e-9);
    }

    #[test]
    fn an_empty_range_is_widened_not_divided_by_zero() {
        let scale = Scale::new(3.0, 3.0, false, 0.0, 100.0);
        assert!(scale.px(3.0).is_finite());
        let log = Scale::new(0.0, 0.0, true, 0.0, 100.0);
        assert!(log.px(1.0).is_finite());
    }

    #[test]
    fn text_is_escaped() {
        assert_eq!(escape(r#"a<b & "c""#), "a&lt;b &amp; &quot;c&quot;");
        assert_eq!(short_number(2.50), "2.5");
        assert_eq!(short_number(-0.0), "0");
        assert_eq!(short_number(1e7), "1e7");
    }

    #[test]
    fn a_histogram_has_bars_an_outline_and_the_markers() {
        let format = |v: f64| format!("{v}");
        let series = [
            HistogramSeries {
                label: "ours".to_owned(),
                bins: vec![(10.0, 20.0, 5), (20.0, 40.0, 100)],
                markers: vec![("p50".to_owned(), 25.0), ("p99".to_owned(), 38.0)],
            },
            HistogramSeries {
                label: "baseline <plain>".to_owned(),
                bins: vec![(10.0, 20.0, 50)],
                markers: vec![],
            },
        ];
        let caption = ["machine: test".to_owned()];
        let svg = histogram(&HistogramChart {
            title: "t",
            caption: &caption,
            x_label: "ns",
            log_x: true,
            x_format: &format,
            series: &series,
        });
        assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("fill-opacity=\"0.55\"").count(), 2, "two bars");
        assert_eq!(svg.matches("<polyline").count(), 1, "one outline");
        assert!(svg.contains(">p50</text>") && svg.contains(">p99</text>"));
        assert!(svg.contains("baseline &lt;plain&gt;"));
        assert!(svg.contains("machine: test"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }

    #[test]
    fn time_series_draw_one_polyline_per_line() {
        let panel = Panel {
            title: "x position".to_owned(),
            y_label: "mm".to_owned(),
            lines: vec![
                Line {
                    label: "desired".to_owned(),
                    points: vec![(0.0, 0.0), (1.0, 2.0)],
                    dashed: true,
                },
                Line {
                    label: "measured".to_owned(),
                    points: vec![(0.0, 0.1), (1.0, 1.9)],
                    dashed: false,
                },
            ],
        };
        let svg = time_series("run", &[], &[panel.clone(), panel]);
        assert_eq!(svg.matches("<polyline").count(), 4);
        assert_eq!(
            svg.matches("stroke-dasharray=\"6 4\"").count(),
            4,
            "lines and legends"
        );
        assert!(!svg.contains("NaN"));
    }
}
