//! The CBCA behaviour on the synchronous driver (driver.rs).

use super::driver::{scenario, Driver};

#[test]
fn example1_commits_the_kernels_coalitions_and_finishes_every_target() {
    let mut d = Driver::new(scenario(1), 0.0, 1);
    assert!(d.run_until(200, |d| d.all_committed()), "no commitment by tick 200");
    let committed_at = d.tick;
    // Robot 1 (index 0) sees its group's coalitions; robot 7 (index 6) the other group's.
    let a = d.coalitions(0);
    let b = d.coalitions(6);
    println!("committed at {committed_at}: group A {a:?}, group B {b:?}");
    assert!(d.run_until(6000, |d| d.all_finished()), "targets left at {}", d.tick);
    println!("finished at {}, {} messages, {} bytes", d.tick, d.sent, d.bytes);
}
