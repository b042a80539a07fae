//! Scenario sections that belong to one paper: what a mission's world side and its behaviours
//! both read. One file per section; the section's validation lives with its owners (the
//! behaviour in the agent crate, the mission in the world crate).

pub mod agents;
pub mod cbca;
pub mod formation;
pub mod hosts;
pub mod hunt;
pub mod hunt_checks;
pub mod roam;

/// The sections of the papers still in the core (moving to papers/: issue 40), registered by
/// default, in the order a resolved scenario lists them.
pub(crate) fn builtin_entries() -> Vec<crate::plugin::SectionEntry> {
    use crate::plugin::SectionEntry;
    vec![
        SectionEntry::of::<formation::FormationSection>(),
        SectionEntry::of::<hunt::HuntSection>(),
        SectionEntry::of::<cbca::CbcaSection>(),
    ]
}
