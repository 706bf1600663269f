//! `motionctl watch`: a live table of every axis, group and signal plus the server's device states
//! and tick statistics.

use core::time::Duration;

use motion_client::ipc::{
    AxisWire, FrameFlags, GroupMotion, MotionFrame, ServerInfo, ServerStats, read_text,
};
use motion_client::{Client, GroupStatus};
use ratatui::Frame;
use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Borders, Cell, Paragraph, Row, Table};

use crate::Service;
use crate::describe::{devices_line, fault_name, flags_with_fault, frame_json, mode_name};
use crate::group::{group_line, groups_json};
use crate::io::signal_table;
use crate::terminal::{print_until_terminated, redraw_until_quit};

/// Runs `watch` until q / Ctrl-C (table) or SIGINT/SIGTERM (`--json`).
pub fn run(client: &Client<Service>, json: bool, interval: Duration) -> anyhow::Result<()> {
    if json {
        return run_json(client, interval);
    }
    redraw_until_quit(client, "watch", interval, |screen| {
        let frame = client.latest()?;
        let info = client.info()?;
        let stats = client.stats()?;
        let restart = client.restart().map(|restart| restart.to_string());
        screen
            .terminal()
            .draw(|ui| draw(ui, &info, &frame, stats.as_deref(), restart.as_deref()))?;
        Ok(())
    })
}

fn run_json(client: &Client<Service>, interval: Duration) -> anyhow::Result<()> {
    let axes: Vec<usize> = (0..client.axes().len()).collect();
    print_until_terminated(client, interval, |info, frame| {
        let mut value = frame_json(info, frame, &axes);
        if !info.groups().is_empty() {
            value["groups"] = groups_json(info, frame);
        }
        value.to_string()
    })
}

fn micros(ns: u64) -> String {
    format!("{:.1}µs", ns as f64 / 1e3)
}

/// Ticks from the current goal to its first request on the wire; `…` while it waits, `-`
/// before any goal.
fn wire_text(wire: &AxisWire) -> String {
    if wire.written() {
        wire.wire_tick.saturating_sub(wire.goal_tick).to_string()
    } else if wire.goal_tick == 0 {
        "-".to_owned()
    } else {
        "…".to_owned()
    }
}

/// Per link: how long ago (at the stats' tick) bytes last went out and came in, and the
/// messages written.
fn links_line(stats: &ServerStats) -> String {
    let ago = |ns: u64| {
        if ns == 0 {
            "never".to_owned()
        } else {
            format!(
                "{:.1} ms ago",
                stats.time_ns.saturating_sub(ns) as f64 / 1e6
            )
        }
    };
    let links: Vec<String> = stats
        .links()
        .iter()
        .zip(stats.link_io())
        .map(|(link, io)| {
            format!(
                "{}: out {} in {} ({} msgs)",
                link.name(),
                ago(io.last_write_ns),
                ago(io.last_read_ns),
                io.transactions
            )
        })
        .collect();
    format!("links: {}", links.join("   "))
}

fn draw(
    ui: &mut Frame<'_>,
    info: &ServerInfo,
    frame: &MotionFrame,
    stats: Option<&ServerStats>,
    restart: Option<&str>,
) {
    let signal_rows = u16::try_from(info.signals().len()).unwrap_or(u16::MAX);
    let signal_height = if signal_rows == 0 {
        0
    } else {
        signal_rows.saturating_add(2)
    };
    let group_lines: Vec<Line<'_>> = (0..info.groups().len())
        .map(|index| match GroupStatus::read(info, frame, index) {
            Ok(status) if status.motion == GroupMotion::Aborted => Line::styled(
                format!("group {}", group_line(&status)),
                Style::default().fg(Color::Red),
            ),
            Ok(status) => Line::raw(format!("group {}", group_line(&status))),
            Err(error) => Line::raw(format!("group #{index}: {error}")),
        })
        .collect();
    let group_height = u16::try_from(group_lines.len()).unwrap_or(u16::MAX);
    let [head, groups, table, signals, foot] = Layout::vertical([
        Constraint::Length(6),
        Constraint::Length(group_height),
        Constraint::Min(3),
        Constraint::Length(signal_height),
        Constraint::Length(1),
    ])
    .areas(ui.area());

    let mut banner = format!(
        "motiond \"{}\"  tick {}  {} Hz  deadman {} ms",
        read_text(&info.name),
        frame.tick,
        info.tick_hz,
        info.command_timeout_ms
    );
    if frame.flags().contains(FrameFlags::ESTOP_LATCHED) {
        banner.push_str("  E-STOP LATCHED");
    }
    let figures = match stats {
        Some(stats) => format!(
            "wake-up p50 {} p99 {} p99.9 {} max {}   work p50 {} max {}   overruns {}   clients {}   \
             lost: frames {} publishes {} replies {} events {} black box {} paths {} setpoints {}",
            micros(stats.wakeup.p50_ns),
            micros(stats.wakeup.p99_ns),
            micros(stats.wakeup.p999_ns),
            micros(stats.wakeup.max_ns),
            micros(stats.work.p50_ns),
            micros(stats.work.max_ns),
            stats.overruns,
            stats.clients,
            stats.frames_lost,
            stats.publish_failures,
            stats.replies_lost,
            stats.events_dropped,
            stats.blackbox_lost,
            stats.paths_dropped,
            stats.setpoints_dropped,
        ),
        None => "tick statistics: none yet (published about once a second)".to_owned(),
    };
    let estop_style = if frame.flags().contains(FrameFlags::ESTOP_LATCHED) {
        Style::default().fg(Color::Red).add_modifier(Modifier::BOLD)
    } else {
        Style::default().add_modifier(Modifier::BOLD)
    };
    let restart_line = match restart {
        Some(restart) => Line::styled(
            restart.to_owned(),
            Style::default().fg(Color::Red).add_modifier(Modifier::BOLD),
        ),
        None => Line::raw(""),
    };
    ui.render_widget(
        Paragraph::new(vec![
            Line::styled(banner, estop_style),
            Line::raw(format!("devices: {}", devices_line(info, frame))),
            Line::raw(figures),
            Line::raw(stats.map_or_else(String::new, links_line)),
            restart_line,
        ])
        .block(Block::default().borders(Borders::BOTTOM)),
        head,
    );

    if group_height > 0 {
        ui.render_widget(Paragraph::new(group_lines), groups);
    }

    let rows =
        info.axes()
            .iter()
            .zip(frame.axes())
            .zip(frame.wire())
            .map(|((axis, state), wire)| {
                let flags = flags_with_fault(state);
                let style = if fault_name(state).is_none() {
                    Style::default()
                } else {
                    Style::default().fg(Color::Red)
                };
                Row::new(vec![
                    Cell::from(axis.name().to_owned()),
                    Cell::from(format!("{:.4}", state.position)),
                    Cell::from(format!("{:.4}", state.velocity)),
                    Cell::from(format!("{:.4}", state.target)),
                    Cell::from(axis.unit().to_owned()),
                    Cell::from(mode_name(state)),
                    Cell::from(
                        frame
                            .tick
                            .saturating_sub(state.last_refresh_tick)
                            .to_string(),
                    ),
                    Cell::from(wire_text(wire)),
                    Cell::from(flags),
                ])
                .style(style)
            });
    let widths = [
        Constraint::Length(14),
        Constraint::Length(12),
        Constraint::Length(12),
        Constraint::Length(12),
        Constraint::Length(6),
        Constraint::Length(14),
        Constraint::Length(6),
        Constraint::Length(6),
        Constraint::Min(10),
    ];
    let header = Row::new([
        "axis", "position", "velocity", "target", "unit", "mode", "age", "wire", "flags",
    ])
    .style(Style::default().add_modifier(Modifier::BOLD));
    ui.render_widget(Table::new(rows, widths).header(header), table);
    if signal_height > 0 {
        ui.render_widget(
            signal_table(info, frame).block(Block::default().borders(Borders::TOP)),
            signals,
        );
    }
    ui.render_widget(
        Paragraph::new("age: ticks since fresh data   wire: ticks goal → link (…: waiting)   q or Ctrl-C quits"),
        foot,
    );
}
