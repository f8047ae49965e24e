#![allow(dead_code)] // each bench uses only some of these helpers
//! Shared timing helpers for the `harness = false` benchmarks: run a closure a few times and
//! print a Markdown table row with the minimum and median wall-clock milliseconds.

use std::time::Instant;

/// Runs `f` once to warm up, then `runs` times, and returns the wall-clock times in ms, sorted.
pub fn time_ms<T>(runs: usize, mut f: impl FnMut() -> T) -> Vec<f64> {
    std::hint::black_box(f());
    let mut times: Vec<f64> = (0..runs.max(1))
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(f());
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times
}

/// Prints the header of the table that [`print_row`] fills.
pub fn print_header(title: &str) {
    println!("\n{title}\n");
    println!("| what | size | runs | min ms | median ms |");
    println!("| --- | --- | --- | --- | --- |");
}

/// Prints one table row for `times` (ms, in any order: the fusion row's come from the
/// pipeline's reports, run by run).
pub fn print_row(what: &str, size: &str, times: &[f64]) {
    let mut sorted = times.to_vec();
    sorted.sort_by(f64::total_cmp);
    let (Some(min), Some(median)) = (sorted.first(), sorted.get(sorted.len() / 2)) else {
        println!("| {what} | {size} | 0 | – | – |");
        return;
    };
    println!(
        "| {what} | {size} | {} | {min:.1} | {median:.1} |",
        sorted.len()
    );
}
