//! `orchestrator view runs/<id>`: the run's replay in the browser; `orchestrator up --view`:
//! the same page on a running run.
//!
//! The page (`page/`: HTML, CSS, JavaScript, embedded with `include_str!`, no CDN) draws the
//! frames of `recording.bin`; see `server.rs` for its routes and `feed.rs` for how a live run's
//! recording is followed.

pub mod feed;
pub mod frame;
pub mod guard;
pub mod http;
pub mod meta;
pub mod server;

use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ViewArgs {
    /// The run folder (holds recording.bin).
    pub run: PathBuf,
    /// Port on 127.0.0.1 (0: any free port; the URL is printed).
    #[arg(long, default_value_t = 0)]
    pub port: u16,
    /// Ticks the page asks for at a time (0: as many as make about 512 KB of frames, 10..=500).
    #[arg(long, default_value_t = 0)]
    pub chunk: usize,
}

/// The run's name on the page: its folder's name.
fn run_name(dir: &std::path::Path) -> String {
    dir.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| dir.display().to_string())
}

pub fn view(a: ViewArgs) -> i32 {
    crate::signals::install();
    let feed = match feed::finished(&a.run.join("recording.bin"), &run_name(&a.run)) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    feed.set_chunk(a.chunk);
    let v = match server::Viewer::start(a.port, feed.clone(), None) {
        Ok(v) => v,
        Err(e) => {
            eprintln!("error: --port: {e}");
            return 2;
        }
    };
    println!("viewer: {}  ({} ticks; Ctrl-C to stop)", v.url, feed.len());
    use std::io::Write;
    let _ = std::io::stdout().flush();
    while !crate::signals::interrupted() {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    v.stop();
    0
}

/// The viewer of a live run (`up --view`): follows `run_dir/recording.bin` from now on.
pub struct Live {
    pub feed: feed::Feed,
    pub viewer: server::Viewer,
}

/// Starts the live viewer of the run about to start in `run_dir` (any recording.bin left
/// there by an earlier run is removed first, so only this run's is followed).
pub fn live(
    run_dir: &std::path::Path,
    port: u16,
    kill: Option<std::sync::Arc<server::KillFn>>,
) -> Result<Live, server::ServeError> {
    let path = run_dir.join("recording.bin");
    let _ = std::fs::remove_file(&path);
    let feed = feed::follow(path, run_name(run_dir));
    let viewer = server::Viewer::start(port, feed.clone(), kill)?;
    Ok(Live { feed, viewer })
}
