//! `motionctl scope AXIS…`: a live plot of position and velocity over a time window.

use core::time::Duration;
use std::collections::VecDeque;

use motion_client::Client;
use motion_client::ipc::AxisInfo;
use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::text::Span;
use ratatui::widgets::{Axis, Block, Borders, Chart, Dataset, GraphType, Paragraph};

use crate::Service;
use crate::terminal::redraw_until_quit;

/// Redraw period.
const REDRAW: Duration = Duration::from_millis(33);
/// Points kept per trace over the window.
const POINTS: f64 = 600.0;

/// One plotted axis: its description and (time s, position, velocity) samples.
struct Trace {
    info: AxisInfo,
    index: usize,
    samples: VecDeque<(f64, f64, f64)>,
}

/// Runs the scope until q / Ctrl-C.
pub fn run(client: &Client<Service>, names: &[String], window: Duration) -> anyhow::Result<()> {
    let mut traces = names
        .iter()
        .map(|name| {
            let axis = client.axis(name)?;
            Ok(Trace {
                info: axis.info(),
                index: axis.index() as usize,
                samples: VecDeque::new(),
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let window_s = window.as_secs_f64().max(0.1);
    let spacing = window_s / POINTS;
    let mut now_s = 0.0;
    redraw_until_quit(client, "scope", REDRAW, |screen| {
        // Every frame that arrived since the last redraw, thinned to the plot's resolution.
        while let Some(frame) = client.try_next_frame()? {
            now_s = frame.time_ns as f64 / 1e9;
            for trace in &mut traces {
                let Some(state) = frame.axes().get(trace.index) else {
                    continue;
                };
                let due = trace
                    .samples
                    .back()
                    .is_none_or(|&(t, _, _)| now_s - t >= spacing || now_s < t);
                if due {
                    trace
                        .samples
                        .push_back((now_s, state.position, state.velocity));
                }
                while trace
                    .samples
                    .front()
                    .is_some_and(|&(t, _, _)| now_s - t > window_s || t > now_s)
                {
                    trace.samples.pop_front();
                }
            }
        }
        screen
            .terminal()
            .draw(|ui| draw(ui, &traces, now_s, window_s))?;
        Ok(())
    })
}

fn bounds(points: &[(f64, f64)], fallback: [f64; 2]) -> [f64; 2] {
    let (low, high) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, y)| {
            (lo.min(y), hi.max(y))
        });
    if !low.is_finite() || !high.is_finite() {
        return fallback;
    }
    let margin = ((high - low) * 0.1).max(1e-3);
    [low - margin, high + margin]
}

fn plot(
    ui: &mut Frame<'_>,
    area: Rect,
    title: String,
    points: &[(f64, f64)],
    x: [f64; 2],
    color: Color,
) {
    let y = bounds(points, [-1.0, 1.0]);
    let label = |value: f64| Span::raw(format!("{value:.3}"));
    let dataset = Dataset::default()
        .marker(Marker::Braille)
        .graph_type(GraphType::Line)
        .style(Style::default().fg(color))
        .data(points);
    let chart = Chart::new(vec![dataset])
        .block(Block::default().title(title).borders(Borders::ALL))
        .x_axis(
            Axis::default()
                .bounds(x)
                .labels([label(x[0] - x[1]), Span::raw("0 s")]),
        )
        .y_axis(Axis::default().bounds(y).labels([
            label(y[0]),
            label((y[0] + y[1]) / 2.0),
            label(y[1]),
        ]));
    ui.render_widget(chart, area);
}

fn draw(ui: &mut Frame<'_>, traces: &[Trace], now_s: f64, window_s: f64) {
    let [plots, foot] =
        Layout::vertical([Constraint::Min(4), Constraint::Length(1)]).areas(ui.area());
    let rows = Layout::vertical(vec![
        Constraint::Ratio(1, traces.len().max(1) as u32);
        traces.len()
    ])
    .split(plots);
    let x = [-window_s, 0.0];
    for (trace, row) in traces.iter().zip(rows.iter()) {
        let [left, right] =
            Layout::horizontal([Constraint::Ratio(1, 2), Constraint::Ratio(1, 2)]).areas(*row);
        let positions: Vec<(f64, f64)> = trace
            .samples
            .iter()
            .map(|&(t, p, _)| (t - now_s, p))
            .collect();
        let velocities: Vec<(f64, f64)> = trace
            .samples
            .iter()
            .map(|&(t, _, v)| (t - now_s, v))
            .collect();
        let name = trace.info.name();
        let unit = trace.info.unit();
        let last = trace.samples.back().copied().unwrap_or((0.0, 0.0, 0.0));
        plot(
            ui,
            left,
            format!(" {name} position {:.4} {unit} ", last.1),
            &positions,
            x,
            Color::Cyan,
        );
        plot(
            ui,
            right,
            format!(" {name} velocity {:.4} {unit}/s ", last.2),
            &velocities,
            x,
            Color::Yellow,
        );
    }
    ui.render_widget(
        Paragraph::new(format!("last {window_s:.1} s   q or Ctrl-C quits")),
        foot,
    );
}
