//! `orchestrator up`'s progress bar: one line that never wraps (its message is cut to the
//! terminal's width). The bar counts the mission's progress where it has one (search:
//! targets found of targets; a search ends when all are found, long before `max_ticks`),
//! else ticks of `max_ticks`; the line also shows the tick, whole ticks per second, robots
//! alive and the radio's deliveries and drops, with digit grouping. It is cleared when the
//! run ends, however it ends (Ctrl-C included): nothing of it is left on the screen.

use indicatif::{
    HumanCount, ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle, TermLike,
};
use std::fmt::Write;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use swarm::scenario::Scenario;

/// Width of the bar itself, in columns: with the spinner, the label and the counts, the
/// line's fixed part stays under 60 columns, so a message fits an 80-column terminal.
const BAR_COLUMNS: usize = 20;

/// Columns left free at the end of the bar's line. A Ctrl-C's echo (`^C`) lands there, on the
/// bar's line, which the clear then wipes; on a full line the echo wrapped to the next one, the
/// clear wiped that one, and the bar stayed on the screen above the summary.
const ECHO_COLUMNS: u16 = 3;

/// stderr as the bar sees it: [`ECHO_COLUMNS`] narrower than the terminal.
#[derive(Debug)]
struct Narrow(console::Term);

impl TermLike for Narrow {
    fn width(&self) -> u16 {
        self.0.size().1.saturating_sub(ECHO_COLUMNS)
    }
    fn move_cursor_up(&self, n: usize) -> std::io::Result<()> {
        self.0.move_cursor_up(n)
    }
    fn move_cursor_down(&self, n: usize) -> std::io::Result<()> {
        self.0.move_cursor_down(n)
    }
    fn move_cursor_right(&self, n: usize) -> std::io::Result<()> {
        self.0.move_cursor_right(n)
    }
    fn move_cursor_left(&self, n: usize) -> std::io::Result<()> {
        self.0.move_cursor_left(n)
    }
    fn write_line(&self, s: &str) -> std::io::Result<()> {
        self.0.write_line(s)
    }
    fn write_str(&self, s: &str) -> std::io::Result<()> {
        self.0.write_str(s)
    }
    fn clear_line(&self) -> std::io::Result<()> {
        self.0.clear_line()
    }
    fn flush(&self) -> std::io::Result<()> {
        self.0.flush()
    }
}

/// What the run reports to the bar, each tick or status.
#[derive(Debug, Clone, Copy, Default)]
pub struct BarStatus {
    pub tick: u64,
    /// The mission's (done, total), (0, 0) for none.
    pub progress: (u32, u32),
    pub alive: u32,
    pub delivered: u64,
    pub dropped: u64,
    /// Real-time mode: deadline misses so far.
    pub misses: Option<u64>,
}

/// The bar of one run.
pub struct Bar {
    pb: ProgressBar,
    robots: u32,
    /// What the mission counts ("targets found"); empty: the bar counts ticks.
    label: &'static str,
    /// The tick, read by the template's rate key.
    tick: Arc<AtomicU64>,
}

impl Bar {
    pub fn new(sc: &Scenario, quiet: bool) -> Bar {
        let label = world::mission::progress_label(sc);
        let tick = Arc::new(AtomicU64::new(0));
        let stderr = console::Term::stderr();
        // Not a terminal (a pipe, a file): no bar, as indicatif's own stderr target does.
        let pb = if quiet || !stderr.is_term() {
            ProgressBar::hidden()
        } else {
            ProgressBar::with_draw_target(
                Some(sc.run.max_ticks),
                ProgressDrawTarget::term_like(Box::new(Narrow(stderr))),
            )
        };
        let t = tick.clone();
        let rate = move |s: &ProgressState, w: &mut dyn Write| {
            let secs = s.elapsed().as_secs_f64();
            let tps = if secs > 0.0 {
                (t.load(Ordering::Relaxed) as f64 / secs).round() as u64
            } else {
                0
            };
            let _ = write!(w, "{}", HumanCount(tps));
        };
        pb.set_style(
            ProgressStyle::with_template(&format!(
                "{{spinner}} {{prefix}} [{{bar:{BAR_COLUMNS}}}] {{human_pos}}/{{human_len}} \
                 {{tps}} ticks/s {{wide_msg}}"
            ))
            .expect("template")
            .with_key("tps", rate)
            .progress_chars("=> "),
        );
        pb.set_prefix("tick");
        Bar {
            pb,
            robots: sc.run.robots,
            label,
            tick,
        }
    }

    pub fn update(&self, s: &BarStatus) {
        self.tick.store(s.tick, Ordering::Relaxed);
        let (done, total) = s.progress;
        let mut msg = String::new();
        if !self.label.is_empty() && total > 0 {
            if self.pb.length() != Some(u64::from(total)) {
                self.pb.set_length(u64::from(total));
                self.pb.set_prefix(self.label);
            }
            self.pb.set_position(u64::from(done));
            msg += &format!("| tick {} ", HumanCount(s.tick));
        } else {
            self.pb.set_position(s.tick);
        }
        msg += &format!("| alive {}/{}", s.alive, self.robots);
        if let Some(m) = s.misses {
            msg += &format!(" | misses {}", HumanCount(m));
        }
        msg += &format!(
            " | msgs {} ok, {} dropped",
            HumanCount(s.delivered),
            HumanCount(s.dropped)
        );
        self.pb.set_message(msg);
    }

    /// Clears the line (the run ended, however).
    pub fn clear(&self) {
        self.pb.finish_and_clear();
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.pb.finish_and_clear();
    }
}

/// `n` with digit grouping: 12,345.
pub fn grouped(n: u64) -> String {
    HumanCount(n).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_grouped_by_thousands() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1_234_567), "1,234,567");
    }
}
