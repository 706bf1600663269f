//! `--plot DIR`: one SVG latency histogram per figure, its same-run baselines overlaid, and
//! `DIR/index.html` with the report's table and the pictures.
//!
//! The histograms are drawn from the distribution files the run wrote
//! ([`Dist::write_percentiles`](crate::Dist::write_percentiles): `value percentile
//! total_count` lines), so a plot shows exactly what the files hold: each line's count (the
//! difference of `total_count`) falls into the bin of its value. Files are grouped into
//! figures by name: `<figure>-motiond` is ours, `<figure>-baseline` and
//! `<figure>-baseline-<which>` are its baselines; a file named otherwise is a figure alone.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::dist::format_ns;
use crate::report::{Report, value};
use crate::svg::{self, Bin, HistogramChart, HistogramSeries};

/// Why the plots could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A file or directory could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// A distribution file is not `value percentile total_count` lines.
    #[error("{path}:{line}: not a `value percentile total_count` line: {text:?}")]
    BadLine {
        /// The file.
        path: PathBuf,
        /// Line number, from 1.
        line: usize,
        /// The line.
        text: String,
    },
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> PlotError + '_ {
    move |source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// One distribution file, read back.
#[derive(Debug, Clone, PartialEq)]
pub struct Distribution {
    /// The file's name without `.txt`.
    pub slug: String,
    /// Its `# title` line.
    pub title: String,
    /// `(value, percentile 0..=100, count of samples up to here)`, ascending.
    pub steps: Vec<(u64, f64, u64)>,
}

impl Distribution {
    /// Parses the text of a distribution file named `slug`.
    pub fn parse(slug: &str, text: &str, path: &Path) -> Result<Self, PlotError> {
        let mut title = slug.to_owned();
        let mut steps = Vec::new();
        for (number, line) in text.lines().enumerate() {
            let line = line.trim();
            if let Some(comment) = line.strip_prefix('#') {
                if number == 0 {
                    title = comment.trim().to_owned();
                }
                continue;
            }
            if line.is_empty() {
                continue;
            }
            let mut fields = line.split_whitespace();
            let parsed = (|| {
                let value = fields.next()?.parse::<u64>().ok()?;
                let percentile = fields.next()?.parse::<f64>().ok()?;
                let total = fields.next()?.parse::<u64>().ok()?;
                Some((value, percentile, total))
            })();
            let Some(step) = parsed.filter(|_| fields.next().is_none()) else {
                return Err(PlotError::BadLine {
                    path: path.to_path_buf(),
                    line: number + 1,
                    text: line.to_owned(),
                });
            };
            steps.push(step);
        }
        Ok(Self {
            slug: slug.to_owned(),
            title,
            steps,
        })
    }

    /// The first value at or above percentile `p` (0..=100), `None` when empty.
    pub fn percentile(&self, p: f64) -> Option<u64> {
        self.steps
            .iter()
            .find(|step| step.1 >= p)
            .or(self.steps.last())
            .map(|step| step.0)
    }

    /// Samples in the distribution.
    pub fn samples(&self) -> u64 {
        self.steps.last().map_or(0, |step| step.2)
    }

    /// `(value, count)`: the samples each line adds.
    fn counts(&self) -> impl Iterator<Item = (u64, u64)> + '_ {
        let mut before = 0;
        self.steps.iter().map(move |&(value, _, total)| {
            let count = total.saturating_sub(before);
            before = before.max(total);
            (value, count)
        })
    }

    /// What the values are, read from the file's name and title.
    fn unit(&self) -> ValueUnit {
        let words = format!("{} {}", self.slug, self.title).to_lowercase();
        if words.contains("ticks") {
            ValueUnit::Ticks
        } else if words.contains("millionths") || words.contains("tracking-error") {
            ValueUnit::Millionths
        } else if words.contains("cpu") || words.contains('%') {
            ValueUnit::Plain
        } else {
            ValueUnit::Ns
        }
    }
}

/// The unit of a figure's values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ValueUnit {
    Ns,
    Ticks,
    Millionths,
    Plain,
}

impl ValueUnit {
    fn label(self) -> &'static str {
        match self {
            Self::Ns => "latency (log scale)",
            Self::Ticks => "ticks",
            Self::Millionths => "millionths of the axis's unit",
            Self::Plain => "value",
        }
    }

    fn format(self, value: f64) -> String {
        match self {
            Self::Ns => format_ns(value.max(0.0) as u64),
            _ => svg::short_number(value),
        }
    }
}

/// Bins of `distributions` on a shared x range: log-spaced when the values span a decade
/// or more above 0, linear otherwise. Returns whether the scale is logarithmic.
fn bin(distributions: &[&Distribution], bins: usize) -> (bool, Vec<Vec<Bin>>) {
    let values = || {
        distributions
            .iter()
            .flat_map(|d| d.counts())
            .filter(|c| c.1 > 0)
    };
    let low = values().map(|c| c.0).min().unwrap_or(0) as f64;
    let high = values().map(|c| c.0).max().unwrap_or(1) as f64;
    let log = low > 0.0 && high / low >= 10.0;
    let edges: Vec<f64> = (0..=bins)
        .map(|i| {
            let t = i as f64 / bins as f64;
            if log {
                10f64.powf(low.log10() + t * (high.log10() - low.log10()))
            } else {
                // Integers (ticks) get bins one apart when few.
                low - 0.5 + t * ((high - low) + 1.0)
            }
        })
        .collect();
    let binned = distributions
        .iter()
        .map(|d| {
            let mut counts = vec![0u64; bins];
            for (value, count) in d.counts() {
                let value = value as f64;
                let slot = edges
                    .partition_point(|edge| *edge <= value)
                    .saturating_sub(1);
                counts[slot.min(bins - 1)] += count;
            }
            (0..bins)
                .map(|i| (edges[i], edges[i + 1], counts[i]))
                .collect()
        })
        .collect();
    (log, binned)
}

/// Splits a slug into its figure and whether it is a baseline.
fn figure_of(slug: &str) -> (&str, bool) {
    if let Some(figure) = slug.strip_suffix("-motiond") {
        return (figure, false);
    }
    // The I/O phase's CPU baseline is its plain peer's.
    if let Some(figure) = slug.strip_suffix("-peer") {
        return (figure, true);
    }
    if let Some(at) = slug.find("-baseline")
        && (slug[at..] == *"-baseline" || slug[at..].starts_with("-baseline-"))
    {
        return (&slug[..at], true);
    }
    (slug, false)
}

/// One picture: a figure's distributions, ours first.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// The picture's file name without `.svg`.
    pub slug: String,
    /// The distributions, ours first, then the baselines by name.
    pub series: Vec<Distribution>,
}

/// Groups distributions into figures (see the module's docs), in name order.
pub fn figures(mut distributions: Vec<Distribution>) -> Vec<Figure> {
    distributions.sort_by(|a, b| {
        let (fa, ba) = figure_of(&a.slug);
        let (fb, bb) = figure_of(&b.slug);
        (fa, ba, &a.slug).cmp(&(fb, bb, &b.slug))
    });
    let mut figures: Vec<Figure> = Vec::new();
    for distribution in distributions {
        let figure = figure_of(&distribution.slug).0.to_owned();
        match figures.last_mut() {
            Some(last) if last.slug == figure => last.series.push(distribution),
            _ => figures.push(Figure {
                slug: figure,
                series: vec![distribution],
            }),
        }
    }
    figures
}

/// The SVG of one figure.
pub fn figure_svg(figure: &Figure, caption: &[String]) -> String {
    let refs: Vec<&Distribution> = figure.series.iter().collect();
    let (log_x, binned) = bin(&refs, 60);
    let unit = figure
        .series
        .first()
        .map_or(ValueUnit::Ns, Distribution::unit);
    let series: Vec<HistogramSeries> = figure
        .series
        .iter()
        .zip(binned)
        .map(|(distribution, bins)| {
            let markers = [("p50", 50.0), ("p99", 99.0), ("p99.9", 99.9)]
                .iter()
                .filter_map(|&(name, p)| {
                    let value = distribution.percentile(p)?;
                    Some((
                        format!("{name} {}", unit.format(value as f64)),
                        value as f64,
                    ))
                })
                .collect();
            HistogramSeries {
                label: format!(
                    "{} ({}, n={})",
                    distribution.title,
                    distribution.slug,
                    distribution.samples()
                ),
                bins,
                markers,
            }
        })
        .collect();
    let format = move |value: f64| unit.format(value);
    svg::histogram(&HistogramChart {
        title: &figure.slug,
        caption,
        x_label: unit.label(),
        log_x,
        x_format: &format,
        series: &series,
    })
}

/// Reads every `*.txt` distribution file of `dir`, in name order.
pub fn read_distributions(dir: &Path) -> Result<Vec<Distribution>, PlotError> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io_error(dir))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|path| path.extension().is_some_and(|e| e == "txt"))
        .collect();
    paths.sort();
    paths
        .iter()
        .map(|path| {
            let text = std::fs::read_to_string(path).map_err(io_error(path))?;
            let slug = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            Distribution::parse(&slug, &text, path)
        })
        .collect()
}

/// The machine and the command, for the captions.
pub fn caption_lines() -> Vec<String> {
    let read = |path: &str| {
        std::fs::read_to_string(path)
            .map(|text| text.trim().to_owned())
            .unwrap_or_else(|_| "?".to_owned())
    };
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find(|line| line.starts_with("model name"))
                .and_then(|line| line.split(':').nth(1))
                .map(|model| model.trim().to_owned())
        })
        .unwrap_or_else(|| "unknown CPU".to_owned());
    let cores = std::thread::available_parallelism().map_or(0, usize::from);
    let command: Vec<String> = std::env::args().collect();
    vec![
        format!(
            "machine: {} (Linux {}), {cpu}, {cores} cores",
            read("/proc/sys/kernel/hostname"),
            read("/proc/sys/kernel/osrelease")
        ),
        format!("command: {}", command.join(" ")),
    ]
}

/// Writes one SVG per figure of the distribution files in `dist_dir` into `plot_dir`, and
/// `plot_dir/index.html` with `report`'s table and the pictures; returns the pictures'
/// file names.
pub fn write(
    dist_dir: &Path,
    plot_dir: &Path,
    report: &Report,
    caption: &[String],
) -> Result<Vec<String>, PlotError> {
    std::fs::create_dir_all(plot_dir).map_err(io_error(plot_dir))?;
    let figures = figures(read_distributions(dist_dir)?);
    let mut names = Vec::new();
    for figure in &figures {
        let name = format!("{}.svg", figure.slug);
        let path = plot_dir.join(&name);
        std::fs::write(&path, figure_svg(figure, caption)).map_err(io_error(&path))?;
        names.push(name);
    }
    // The distribution files beside the page, or where --out put them.
    let same_dir = std::fs::canonicalize(dist_dir).ok() == std::fs::canonicalize(plot_dir).ok();
    let files_prefix = if same_dir {
        String::new()
    } else {
        let absolute = std::fs::canonicalize(dist_dir).map_err(io_error(dist_dir))?;
        format!("file://{}/", absolute.display())
    };
    let path = plot_dir.join("index.html");
    std::fs::write(
        &path,
        index_html(report, caption, &figures, &names, &files_prefix),
    )
    .map_err(io_error(&path))?;
    Ok(names)
}

/// The report's rows as an HTML table: p50 / p99 / p99.9 of ours and the baseline, and
/// the ratios.
fn rows_table(report: &Report) -> String {
    let mut html = String::from(
        "<table>\n<tr><th>#</th><th>figure</th><th>ours p50 / p99 / p99.9</th>\
         <th>baseline p50 / p99 / p99.9</th><th>ratio p50</th><th>ratio p99</th></tr>\n",
    );
    let cell = |unit, summary: Option<crate::Summary>| match summary {
        Some(s) if !s.is_empty() => format!(
            "{} / {} / {}",
            value(unit, s.p50),
            value(unit, s.p99),
            value(unit, s.p999)
        ),
        Some(_) => "no samples".to_owned(),
        None => "none".to_owned(),
    };
    for (index, row) in report.rows.iter().enumerate() {
        let (p50, p99) = row
            .ratios()
            .map_or((String::new(), String::new()), |(a, b)| {
                (format!("×{a:.2}"), format!("×{b:.2}"))
            });
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{p50}</td><td>{p99}</td></tr>",
            index + 1,
            svg::escape(&row.figure),
            svg::escape(&cell(row.unit, Some(row.ours))),
            svg::escape(&cell(row.unit, row.baseline)),
        );
    }
    html.push_str("</table>\n");
    html
}

/// The page: the report's rows as a table, each picture, then the full text report. Its
/// script counts the pictures that loaded into `<body data-loaded="N" data-images="M">`
/// (read by `scripts/check-plots`). The distribution files are linked as
/// `files_prefix` + their name.
pub fn index_html(
    report: &Report,
    caption: &[String],
    figures: &[Figure],
    names: &[String],
    files_prefix: &str,
) -> String {
    let mut html = String::new();
    html.push_str(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>motiond latency bench</title>\n<style>\nbody { font-family: sans-serif; \
         margin: 2em; }\npre { background: #f6f6f6; padding: 1em; overflow-x: auto; }\n\
         table { border-collapse: collapse; font-size: 13px; }\n\
         td, th { border: 1px solid #ccc; padding: 2px 6px; text-align: left; }\n\
         figure { margin: 2em 0; }\nimg { max-width: 100%; border: 1px solid #ccc; }\n\
         </style>\n</head>\n<body data-loaded=\"0\">\n<h1>motiond latency bench</h1>\n",
    );
    for line in caption {
        let _ = writeln!(html, "<p>{}</p>", svg::escape(line));
    }
    let _ = writeln!(
        html,
        "<h2>Figures</h2>\n<p>Ratio = ours ÷ baseline; the full report, with each \
         baseline's description and the notes, is <a href=\"#report\">below the \
         pictures</a>.</p>\n{}",
        rows_table(report)
    );
    let _ = writeln!(
        html,
        "<h2>Distributions</h2>\n<p>Each picture: the figure's histogram (counts on a log \
         scale) with its same-run baselines overlaid; dashed lines mark p50, p99 and p99.9.</p>"
    );
    for (figure, name) in figures.iter().zip(names) {
        let files: Vec<String> = figure
            .series
            .iter()
            .map(|d| {
                let slug = svg::escape(&d.slug);
                format!(
                    "<a href=\"{}{slug}.txt\">{slug}.txt</a>",
                    svg::escape(files_prefix)
                )
            })
            .collect();
        let _ = writeln!(
            html,
            "<figure id=\"{slug}\">\n<img src=\"{src}\" alt=\"{slug}\">\n\
             <figcaption>{slug}: {files}</figcaption>\n</figure>",
            slug = svg::escape(&figure.slug),
            src = svg::escape(name),
            files = files.join(", ")
        );
    }
    let _ = writeln!(
        html,
        "<h2 id=\"report\">Report</h2>\n<pre>{}</pre>",
        svg::escape(&report.table())
    );
    html.push_str(
        "<script>\nfunction countLoaded() {\n  const images = Array.from(document.images);\n  \
         const loaded = images.filter((img) => img.complete && img.naturalWidth > 0).length;\n  \
         document.body.dataset.loaded = String(loaded);\n  \
         document.body.dataset.images = String(images.length);\n}\n\
         window.addEventListener('load', countLoaded);\ncountLoaded();\n</script>\n\
         </body>\n</html>\n",
    );
    html
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dist::Dist;

    fn distribution(slug: &str, samples: &[(u64, u64)]) -> Distribution {
        let mut dist = Dist::new();
        for &(value, count) in samples {
            dist.record_n(value, count);
        }
        let dir = std::env::temp_dir().join(format!("motion-bench-plots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join(format!("{slug}.txt"));
        dist.write_percentiles(&path, &format!("{slug} title"))
            .expect("write");
        let text = std::fs::read_to_string(&path).expect("read");
        Distribution::parse(slug, &text, &path).expect("parse")
    }

    #[test]
    fn a_file_reads_back_with_its_counts_and_percentiles() {
        let d = distribution(
            "frame-waitset-motiond",
            &[(1000, 90), (5000, 9), (90_000, 1)],
        );
        assert_eq!(d.title, "frame-waitset-motiond title");
        assert_eq!(d.samples(), 100);
        assert_eq!(d.counts().map(|c| c.1).sum::<u64>(), 100);
        let near = |value: u64, want: u64| value.abs_diff(want) * 1000 <= want;
        assert!(near(d.percentile(50.0).expect("p50"), 1000));
        assert!(near(d.percentile(99.0).expect("p99"), 5000));
        assert!(near(d.percentile(99.9).expect("p99.9"), 90_000));
    }

    #[test]
    fn a_bad_line_is_named() {
        let error =
            Distribution::parse("x", "# t\n1 50.0 3\nfoo\n", Path::new("x.txt")).expect_err("bad");
        assert!(error.to_string().contains("x.txt:3"), "{error}");
    }

    #[test]
    fn files_group_into_figures_ours_first() {
        let slugs = [
            "command-rtt-baseline-busy",
            "command-rtt-baseline-ticking",
            "command-rtt-motiond",
            "wakeup-baseline-sleeper",
            "tracking-error-gantry-x",
        ];
        let all = slugs.iter().map(|s| distribution(s, &[(10, 1)])).collect();
        let figures = figures(all);
        let shape: Vec<(String, Vec<String>)> = figures
            .iter()
            .map(|f| {
                let series = f.series.iter().map(|d| d.slug.clone()).collect();
                (f.slug.clone(), series)
            })
            .collect();
        assert_eq!(
            shape,
            vec![
                (
                    "command-rtt".to_owned(),
                    vec![
                        "command-rtt-motiond".to_owned(),
                        "command-rtt-baseline-busy".to_owned(),
                        "command-rtt-baseline-ticking".to_owned(),
                    ]
                ),
                (
                    "tracking-error-gantry-x".to_owned(),
                    vec!["tracking-error-gantry-x".to_owned()]
                ),
                (
                    "wakeup".to_owned(),
                    vec!["wakeup-baseline-sleeper".to_owned()]
                ),
            ]
        );
    }

    #[test]
    fn bins_keep_every_sample() {
        let ours = distribution("a-motiond", &[(1000, 90), (5000, 9), (90_000, 1)]);
        let base = distribution("a-baseline", &[(800, 50), (2000, 50)]);
        let (log, binned) = bin(&[&ours, &base], 60);
        assert!(log);
        assert_eq!(binned[0].iter().map(|b| b.2).sum::<u64>(), 100);
        assert_eq!(binned[1].iter().map(|b| b.2).sum::<u64>(), 100);
        let ticks = distribution("t-ticks-motiond", &[(0, 5), (1, 5)]);
        let (log, binned) = bin(&[&ticks], 10);
        assert!(!log, "0 is on a linear scale");
        assert_eq!(binned[0].iter().map(|b| b.2).sum::<u64>(), 10);
    }

    #[test]
    fn the_page_has_every_picture_and_the_counting_script() {
        let figures = figures(vec![
            distribution("page-a-motiond", &[(1000, 3)]),
            distribution("page-b-motiond", &[(1000, 3)]),
        ]);
        let names = vec!["a.svg".to_owned(), "b.svg".to_owned()];
        let mut report = Report::default();
        report.rows.push(crate::report::Row {
            figure: "row <x>".to_owned(),
            unit: crate::report::Unit::Ns,
            ours: crate::Summary {
                samples: 3,
                p50: 2000,
                p99: 4000,
                p999: 4000,
                max: 4000,
            },
            baseline: Some(crate::Summary {
                samples: 3,
                p50: 1000,
                p99: 1000,
                p999: 1000,
                max: 1000,
            }),
            baseline_label: "plain".to_owned(),
            note: String::new(),
        });
        let html = index_html(&report, &["machine: m".to_owned()], &figures, &names, "");
        assert_eq!(html.matches("<img ").count(), 2);
        assert!(html.contains("<td>row &lt;x&gt;</td>"), "{html}");
        assert!(html.contains("<td>×2.00</td><td>×4.00</td>"), "{html}");
        assert!(html.contains("1. row &lt;x&gt;"), "the text report too");
        assert!(html.contains("dataset.loaded"));
        let svg = figure_svg(&figures[0], &[]);
        assert!(svg.contains("p99.9"));
    }
}
