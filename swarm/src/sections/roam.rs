//! The roaming behaviour's scenario section (`[roam]`): virtual-force roaming (docs/search.md
//! eq. 5), no mission.

use serde::{Deserialize, Serialize};

#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RoamParams {
    pub l_r: f64,
    pub c: f64,
    pub l1: f64,
    pub obstacle_range: f64,
    pub obstacle_weight: f64,
    /// Bytes of bulk payload in each beacon (a `Blob`, received zero-copy); 0 = none.
    #[serde(default)]
    pub payload_bytes: u32,
}

/// Bytes a roam beacon adds to its payload: the position and the payload's length.
pub const ROAM_BEACON_OVERHEAD: u32 = 16 + 5;
