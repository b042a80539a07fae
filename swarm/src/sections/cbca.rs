//! The `[cbca]` section (thesis 003 chapter 4: CBCA's parameters, target and robot rows), as
//! TOML: read and validated by the agent crate's `cbca` behaviour. Left out when empty.

use serde::{Deserialize, Serialize};

#[derive(Serialize, Deserialize, Clone, Debug, Default, PartialEq)]
#[serde(transparent)]
pub struct CbcaSection(pub toml::Table);

impl crate::plugin::Section for CbcaSection {
    const NAME: &'static str = "cbca";
    fn absent() -> Option<Self> {
        Some(CbcaSection::default())
    }
    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}
