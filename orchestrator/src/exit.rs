//! The exit codes of `orchestrator` (README, "Exit codes"): what a script learns of a run.

/// The run ended by itself and its mission is accomplished (search: every target found;
/// hunt: every evader captured; formation: formed; roam, which has no goal: it ran its
/// `run.max_ticks` with a robot alive). Every other command: it did what it was asked.
pub const COMPLETE: i32 = 0;
/// Something failed: a process of the run, a robot whose agent could not start, an output
/// that could not be written (the file is named), a registry that is not this user's.
pub const FAILED: i32 = 1;
/// Bad input (a flag, a scenario file, the environment): refused before anything started.
pub const BAD_INPUT: i32 = 2;
/// The run ended by itself without accomplishing its mission: `run.max_ticks` reached
/// first, or every robot dead.
pub const MISSION_NOT_COMPLETE: i32 = 3;
// Interrupted: 128 + the signal, 130 (SIGINT, Ctrl-C) or 143 (SIGTERM): `signals::exit_code`.
