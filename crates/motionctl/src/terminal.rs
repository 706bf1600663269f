//! The full-screen terminal of `watch`, `io watch` and `scope`: raw mode and the alternate
//! screen, restored however the command ends; the redraw loop they share, and the line
//! loop of their `--json` forms.

use core::time::Duration;
use std::io::{self, IsTerminal as _, Stdout};

use anyhow::{Context as _, bail};
use motion_client::ipc::{MotionFrame, ServerInfo};
use motion_client::{Client, ClientError};
use ratatui::Terminal;
use ratatui::backend::CrosstermBackend;
use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use ratatui::crossterm::execute;
use ratatui::crossterm::terminal::{
    EnterAlternateScreen, LeaveAlternateScreen, disable_raw_mode, enable_raw_mode,
};

use crate::Service;

/// A terminal in raw mode on the alternate screen; restored when dropped.
pub struct Screen {
    terminal: Terminal<CrosstermBackend<Stdout>>,
}

impl core::fmt::Debug for Screen {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Screen").finish_non_exhaustive()
    }
}

impl Screen {
    /// Takes over the terminal; fails clearly when stdout is not one.
    pub fn enter(what: &str) -> anyhow::Result<Self> {
        if !io::stdout().is_terminal() {
            bail!(
                "{what} draws on a terminal and stdout is not one; use `status --json` or `watch --json` in scripts"
            );
        }
        enable_raw_mode().context("switch the terminal to raw mode")?;
        let mut stdout = io::stdout();
        if let Err(error) = execute!(stdout, EnterAlternateScreen) {
            let _ = disable_raw_mode();
            return Err(error).context("enter the alternate screen");
        }
        let terminal = match Terminal::new(CrosstermBackend::new(stdout)) {
            Ok(terminal) => terminal,
            Err(error) => {
                let _ = execute!(io::stdout(), LeaveAlternateScreen);
                let _ = disable_raw_mode();
                return Err(error).context("open the terminal");
            }
        };
        Ok(Self { terminal })
    }

    /// The ratatui terminal to draw on.
    pub fn terminal(&mut self) -> &mut Terminal<CrosstermBackend<Stdout>> {
        &mut self.terminal
    }
}

impl Drop for Screen {
    fn drop(&mut self) {
        let _ = disable_raw_mode();
        let _ = execute!(self.terminal.backend_mut(), LeaveAlternateScreen);
        let _ = self.terminal.show_cursor();
    }
}

/// Takes over the terminal for `what` and calls `redraw` every `interval` until the user
/// quits (q, Esc, Ctrl-C) or the process is asked to terminate (SIGINT/SIGTERM).
pub fn redraw_until_quit(
    client: &Client<Service>,
    what: &str,
    interval: Duration,
    mut redraw: impl FnMut(&mut Screen) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut screen = Screen::enter(what)?;
    loop {
        redraw(&mut screen)?;
        if quit_requested(interval)? {
            return Ok(());
        }
        match client.check_interrupted() {
            Err(ClientError::Interrupted) => return Ok(()),
            other => other?,
        }
    }
}

/// Prints one line, `line` of the server's description and its newest frame, every
/// `interval` until the process is asked to terminate (SIGINT/SIGTERM).
pub fn print_until_terminated(
    client: &Client<Service>,
    interval: Duration,
    mut line: impl FnMut(&ServerInfo, &MotionFrame) -> String,
) -> anyhow::Result<()> {
    loop {
        let frame = client.latest()?;
        let info = client.info()?;
        out!("{}", line(&info, &frame));
        drop(frame);
        if client.node().wait(interval).is_err() {
            return Ok(());
        }
    }
}

/// Waits up to `timeout` for input; true when the user asked to quit (q, Esc, Ctrl-C).
pub fn quit_requested(timeout: Duration) -> anyhow::Result<bool> {
    if !event::poll(timeout).context("read the keyboard")? {
        return Ok(false);
    }
    // Take everything that is waiting, so a burst of keys does not lag the display.
    loop {
        if let Event::Key(key) = event::read().context("read the keyboard")?
            && key.kind != KeyEventKind::Release
        {
            let ctrl_c =
                key.modifiers.contains(KeyModifiers::CONTROL) && key.code == KeyCode::Char('c');
            if ctrl_c || matches!(key.code, KeyCode::Char('q' | 'Q') | KeyCode::Esc) {
                return Ok(true);
            }
        }
        if !event::poll(Duration::ZERO).context("read the keyboard")? {
            return Ok(false);
        }
    }
}
