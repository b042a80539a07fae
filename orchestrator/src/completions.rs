//! The command line as clap sees it, with the embedded scenario's values shown as the
//! defaults of `up`'s scenario flags, and `orchestrator completions SHELL`, which prints the
//! shell's completion script of it (clap_complete).

use clap::{Args, CommandFactory};

#[derive(Args, Debug)]
pub struct CompletionsArgs {
    /// The shell whose completion script to print.
    pub shell: clap_complete::Shell,
}

/// A scenario key's value in the embedded default scenario, as TOML prints it; None for a key
/// it leaves out, a switch (false) or an empty list.
fn embedded_default(key: &str) -> Option<String> {
    let sc = toml::Value::try_from(swarm::scenario::Scenario::default()).ok()?;
    let v = key.split('.').try_fold(&sc, |v, k| v.get(k))?;
    match v {
        toml::Value::Boolean(_) => None,
        toml::Value::Array(a) if a.is_empty() => None,
        toml::Value::String(s) => Some(s.clone()),
        v => Some(v.to_string()),
    }
}

/// The widest help: a wider terminal still gets lines of at most this many columns.
const HELP_COLUMNS: usize = 80;

/// The orchestrator's command line; `up`'s flags that set a scenario key say the embedded
/// scenario's value: `[scenario: run.robots, default 12]`.
pub fn command() -> clap::Command {
    let cli = crate::Cli::command().max_term_width(HELP_COLUMNS);
    cli.mut_subcommand("up", |mut up| {
        for (key, flag) in crate::up::FLAG_KEYS {
            let Some(default) = embedded_default(key) else {
                continue;
            };
            let id = flag.trim_start_matches("--").replace('-', "_");
            let marker = format!("[scenario: {key}]");
            up = up.mut_arg(id, |arg| {
                let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
                let shown = format!("[scenario: {key}, default {default}]");
                arg.help(help.replace(&marker, &shown))
            });
        }
        up
    })
}

pub fn print(a: CompletionsArgs) -> i32 {
    clap_complete::generate(
        a.shell,
        &mut command(),
        "orchestrator",
        &mut std::io::stdout(),
    );
    0
}

#[cfg(test)]
mod tests {
    use super::*;
    use search::SearchScenario;

    /// Every subcommand and argument, hidden ones left out: (path, argument id, help).
    fn walk(c: &clap::Command, path: &str, out: &mut Vec<(String, String, String)>) {
        for a in c.get_arguments().filter(|a| !a.is_hide_set()) {
            let help = a.get_help().map(|h| h.to_string()).unwrap_or_default();
            out.push((path.to_string(), a.get_id().to_string(), help));
        }
        for s in c.get_subcommands().filter(|s| !s.is_hide_set()) {
            walk(s, &format!("{path} {}", s.get_name()), out);
        }
    }

    #[test]
    fn every_argument_of_every_subcommand_has_help() {
        let mut c = command();
        c.build();
        let mut all = Vec::new();
        walk(&c, "orchestrator", &mut all);
        let empty: Vec<String> = all
            .iter()
            .filter(|(_, _, h)| h.trim().is_empty())
            .map(|(p, id, _)| format!("{p} {id}"))
            .collect();
        assert!(empty.is_empty(), "arguments without help: {empty:?}");
        assert!(all.len() > 50, "{} arguments walked", all.len());
    }

    #[test]
    fn up_shows_the_embedded_scenarios_defaults() {
        let c = command();
        let up = c.find_subcommand("up").unwrap();
        let help = |id: &str| {
            up.get_arguments()
                .find(|a| a.get_id() == id)
                .and_then(|a| a.get_help())
                .map(|h| h.to_string())
                .unwrap()
        };
        let sc = swarm::scenario::Scenario::default();
        assert!(
            help("robots").contains(&format!("default {}]", sc.run.robots)),
            "{}",
            help("robots")
        );
        assert!(help("max_ticks").contains(&format!("default {}]", sc.run.max_ticks)));
        assert!(help("mode").contains(&format!("default {}]", sc.search().mode)));
    }
}
