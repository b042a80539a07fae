//! The composition of the built-in binaries: the core and its plug-ins, one line each. Every
//! binary of this package runs with [`Builtin`]; a user's crate composes its own the same way
//! (README, "Your own plug-in").

/// The built-in plug-ins, in the order their scenario sections appear in a resolved scenario.
pub type Builtin = (
    // the multi-target search paper (papers/search)
    search::Search,
    // roam, faulty, keeper and, until they move to papers/ (issue 40), the formation and
    // hunting papers' behaviours and sections
    agent::behaviours::Builtin,
);
