//! `orchestrator bench` (filled in below).
use clap::Args;

#[derive(Args, Debug)]
pub struct BenchArgs {}

#[derive(Args, Debug)]
pub struct ChildArgs {}

pub fn bench(_a: BenchArgs) -> i32 {
    eprintln!("not yet");
    1
}

pub fn child(_a: ChildArgs) -> i32 {
    1
}
