//! CBCA end to end (thesis 003 chapter 4, Example 1): every robot a real process, the
//! coalitions formed over the real radio with no auctioneer, the hunt mission captures every
//! evader; the in-process executor records the same run.

use e2e::*;
use std::path::PathBuf;

#[test]
fn example1_in_processes_encircles_every_target_as_in_process() {
    let _g = serial();
    let sc = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../configs/hunt-cbca.toml");
    let a = tmp_dir("cbca-p");
    let b = tmp_dir("cbca-i");
    for (dir, exec) in [(&a, "processes"), (&b, "inprocess")] {
        let o = up(
            &["--scenario", sc.to_str().unwrap(), "--executor", exec],
            dir,
        );
        assert!(o.status.success(), "{exec}: {}", stderr(&o));
    }
    let s = summary(&a);
    assert_eq!(s["end"], "all evaders captured", "{s}");
    let m = &s["mission"]["hunt"];
    assert_eq!(
        (m["evaders"].as_u64(), m["captured"].as_u64()),
        (Some(4), Some(4))
    );
    let rec = |d: &PathBuf| std::fs::read(d.join("recording.bin")).expect("recording.bin");
    assert!(rec(&a) == rec(&b), "the executors differ");
    assert_left_nothing(&a);
}
