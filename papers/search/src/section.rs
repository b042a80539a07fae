//! The search paper's scenario section (`[search]`, docs/search.md) and what its world mission
//! and its behaviour share: the display states and the kind of entity robots sense.

use serde::{Deserialize, Serialize};

/// The multi-target search scenario (docs/search.md): targets, their signal, the mode.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SearchParams {
    /// Obstacle layer B (BSOA) or S (SVF), then search layer T (TPEPSO), E (EPSO), A (ARBA).
    pub mode: String,
    pub targets: u32,
    pub target_region: [f64; 4],
    pub target_clearance: f64,
    pub signal_m: f64,
    pub signal_q: f64,
    pub noise_sigma: f64,
    pub l_t: f64,
    pub found_distance: f64,
    pub end_when_all_found: bool,
    /// The behaviour's own parameters (search::kernels::Params), validated by the agent crate.
    #[serde(default)]
    pub kernels: toml::Table,
}

/// Every scenario has `[search]`: the embedded default scenario's.
impl swarm::plugin::Section for SearchParams {
    const NAME: &'static str = "search";
}

/// A scenario's `[search]` (`use search::SearchScenario` to call `sc.search()`).
pub trait SearchScenario {
    fn search(&self) -> &SearchParams;
    fn search_mut(&mut self) -> &mut SearchParams;
}

impl SearchScenario for swarm::scenario::Scenario {
    fn search(&self) -> &SearchParams {
        self.section::<SearchParams>()
            .expect("every scenario has [search] (the embedded default's)")
    }
    fn search_mut(&mut self) -> &mut SearchParams {
        self.sections
            .get_mut::<SearchParams>()
            .expect("every scenario has [search] (the embedded default's)")
    }
}

/// Search modes (Table 3).
pub const SEARCH_MODES: &[&str] = &["BT", "BE", "BA", "ST", "SE", "SA"];

/// Display states of the search behaviour (paper Fig. 6's colours): roaming is
/// `frames::STATE_DEFAULT` (0).
pub const STATE_COOPERATIVE: u32 = 1;
pub const STATE_DECLARED: u32 = 2;

/// Most target signals one robot senses in a tick (targets in id order, its own finds first).
pub const MAX_SIGNALS: usize = 16;

/// The kind of entity a search robot senses: a target's signal (eq. 33), no position.
pub const ENTITY_SIGNAL: u32 = 0;
