#![allow(dead_code)] // each bench uses only some of these helpers
//! Shared helpers for the `harness = false` benchmarks: run a closure a few times and print a
//! Markdown table row with the minimum and median wall-clock milliseconds; and a counting
//! allocator ([`PeakHeap`]) for a bench that reports peak heap memory.

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

/// The system allocator, counting the bytes it has out and the most it had out at once: a
/// bench registers it as its `#[global_allocator]` and measures with [`PeakHeap::peak_during`].
pub struct PeakHeap {
    current: std::sync::atomic::AtomicUsize,
    peak: std::sync::atomic::AtomicUsize,
}

impl PeakHeap {
    /// A counter with nothing allocated.
    pub const fn new() -> Self {
        PeakHeap {
            current: std::sync::atomic::AtomicUsize::new(0),
            peak: std::sync::atomic::AtomicUsize::new(0),
        }
    }

    /// Peak heap bytes that `f` adds above what is allocated when it starts (this being the
    /// bench's global allocator; one thread).
    pub fn peak_during<T>(&self, f: impl FnOnce() -> T) -> usize {
        use std::sync::atomic::Ordering::SeqCst;
        let base = self.current.load(SeqCst);
        self.peak.store(base, SeqCst);
        std::hint::black_box(f());
        self.peak.load(SeqCst).saturating_sub(base)
    }

    /// `ptr`, after counting its `size` bytes when it is not null.
    fn counted(&self, ptr: *mut u8, size: usize) -> *mut u8 {
        use std::sync::atomic::Ordering::SeqCst;
        if !ptr.is_null() {
            let now = self.current.fetch_add(size, SeqCst) + size;
            self.peak.fetch_max(now, SeqCst);
        }
        ptr
    }

    /// Counts `size` bytes given back.
    fn released(&self, size: usize) {
        self.current
            .fetch_sub(size, std::sync::atomic::Ordering::SeqCst);
    }
}

// SAFETY: every call is passed on to the system allocator unchanged; the counters only
// observe the sizes.
unsafe impl std::alloc::GlobalAlloc for PeakHeap {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc` is passed on.
        self.counted(unsafe { std::alloc::System.alloc(layout) }, layout.size())
    }

    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc_zeroed` is passed on.
        self.counted(
            unsafe { std::alloc::System.alloc_zeroed(layout) },
            layout.size(),
        )
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, size: usize) -> *mut u8 {
        // SAFETY: the caller's contract for `realloc` is passed on.
        let moved = unsafe { std::alloc::System.realloc(ptr, layout, size) };
        if !moved.is_null() {
            self.released(layout.size());
        }
        self.counted(moved, size)
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: the caller's contract for `dealloc` is passed on.
        unsafe { std::alloc::System.dealloc(ptr, layout) };
        self.released(layout.size());
    }
}
