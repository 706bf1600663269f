//! `record --plot FILE.svg`: per recorded axis, desired and measured position, then desired
//! and measured velocity, over the recording's server time (the SVG charts of
//! `motion_bench::svg`).

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use motion_bench::svg::{self, Line, Panel};
use motion_client::Client;
use motion_client::ipc::{MotionFrame, read_text};

use crate::Service;
use crate::record_output::Recording;

/// Points kept per line: a longer recording keeps every n-th tick (the picture is at most
/// 800 px wide), so a long run still makes a file a browser opens quickly.
const MAX_POINTS: usize = 2000;

/// One axis's four series, one point per tick: (s, desired pos, measured pos, desired vel,
/// measured vel).
#[derive(Debug)]
struct AxisSeries {
    index: usize,
    name: String,
    unit: String,
    samples: Vec<[f64; 5]>,
}

/// A plot being gathered; drawn by `finish`.
#[derive(Debug)]
pub struct PlotRecording {
    path: PathBuf,
    server: String,
    axes: Vec<AxisSeries>,
    first_ns: Option<u64>,
}

impl PlotRecording {
    /// Checks the file can be created (so a bad path fails before recording).
    pub fn create(client: &Client<Service>, axes: &[usize], path: &Path) -> anyhow::Result<Self> {
        std::fs::File::create(path).context("create the file")?;
        let info = client.info()?;
        let axes = axes
            .iter()
            .map(|&index| {
                let axis = info.axes().get(index).context("axis list changed")?;
                Ok(AxisSeries {
                    index,
                    name: axis.name().to_owned(),
                    unit: axis.unit().to_owned(),
                    samples: Vec::new(),
                })
            })
            .collect::<anyhow::Result<_>>()?;
        Ok(Self {
            path: path.to_path_buf(),
            server: read_text(&info.name).to_owned(),
            axes,
            first_ns: None,
        })
    }
}

/// Every n-th sample so that at most [`MAX_POINTS`] remain, the last one always kept.
fn thin<T: Copy>(samples: &[T]) -> Vec<T> {
    let step = samples.len().div_ceil(MAX_POINTS).max(1);
    let mut kept: Vec<T> = samples.iter().step_by(step).copied().collect();
    if let Some(&last) = samples.last()
        && !(samples.len() - 1).is_multiple_of(step)
    {
        kept.push(last);
    }
    kept
}

impl Recording for PlotRecording {
    fn frame(&mut self, frame: &MotionFrame) -> anyhow::Result<()> {
        let first = *self.first_ns.get_or_insert(frame.time_ns);
        let seconds = frame.time_ns.saturating_sub(first) as f64 / 1e9;
        for axis in &mut self.axes {
            let state = frame.axes().get(axis.index).copied().unwrap_or_default();
            axis.samples.push([
                seconds,
                state.desired_position,
                state.position,
                state.desired_velocity,
                state.velocity,
            ]);
        }
        Ok(())
    }

    fn finish(self: Box<Self>) -> anyhow::Result<()> {
        let mut panels = Vec::new();
        for axis in &self.axes {
            let samples = thin(&axis.samples);
            let series = |column: usize| samples.iter().map(|s| (s[0], s[column])).collect();
            for (what, unit, desired, measured) in [
                ("position", axis.unit.clone(), 1, 2),
                ("velocity", format!("{}/s", axis.unit), 3, 4),
            ] {
                panels.push(Panel {
                    title: format!("{} {what}", axis.name),
                    y_label: unit,
                    lines: vec![
                        Line {
                            label: "desired".to_owned(),
                            points: series(desired),
                            dashed: true,
                        },
                        Line {
                            label: "measured".to_owned(),
                            points: series(measured),
                            dashed: false,
                        },
                    ],
                });
            }
        }
        let ticks = self.axes.first().map_or(0, |a| a.samples.len());
        let caption = [
            format!(
                "motiond \"{}\": {ticks} ticks recorded by motionctl record",
                self.server
            ),
            format!(
                "command: {}",
                std::env::args().collect::<Vec<_>>().join(" ")
            ),
        ];
        let title = format!("motiond/{}: desired and measured, per axis", self.server);
        std::fs::write(&self.path, svg::time_series(&title, &caption, &panels))?;
        Ok(())
    }

    fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_the_ends_and_at_most_the_limit() {
        let samples: Vec<usize> = (0..5001).collect();
        let kept = thin(&samples);
        assert!(kept.len() <= MAX_POINTS + 1);
        assert_eq!(kept.first(), Some(&0));
        assert_eq!(kept.last(), Some(&5000));
        let few: Vec<usize> = (0..10).collect();
        assert_eq!(thin(&few), few);
    }
}
