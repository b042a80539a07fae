//! CBCA end to end (thesis 003 chapter 4, Example 1): every robot a real process, the
//! coalitions formed over the real radio with no auctioneer, the hunt mission captures every
//! evader; the in-process executor records the same run.

use e2e::*;

#[test]
fn example1_in_processes_encircles_every_target_as_in_process() {
    let _g = serial();
    let (a, b) = up_in_both_executors("hunt-cbca.toml", "cbca");
    let s = summary(&a);
    assert_eq!(s["end"], "all evaders captured", "{s}");
    let m = &s["mission"]["hunt"];
    assert_eq!(
        (m["evaders"].as_u64(), m["captured"].as_u64()),
        (Some(4), Some(4))
    );
    assert!(same_recording(&a, &b), "the executors differ");
    assert_left_nothing(&a);
}
