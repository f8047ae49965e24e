//! Out-of-memory reporting for the page. A wasm module whose allocation fails aborts (a
//! `RuntimeError: unreachable` in JavaScript, the same as a panic); this allocator remembers the
//! size of the last allocation that failed, so the worker can tell the user "out of memory"
//! instead of "crashed". It forwards everything to the system allocator.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use wasm_bindgen::prelude::*;

/// Bytes of the last allocation that failed; 0 while none has.
static FAILED_BYTES: AtomicUsize = AtomicUsize::new(0);

/// The system allocator, noting the size of any allocation it cannot make.
struct Reporting;

impl Reporting {
    fn note(pointer: *mut u8, bytes: usize) -> *mut u8 {
        if pointer.is_null() {
            FAILED_BYTES.store(bytes, Ordering::Relaxed);
        }
        pointer
    }
}

// SAFETY: every call is forwarded unchanged to `System`, which upholds the contract.
unsafe impl GlobalAlloc for Reporting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract, which we pass on.
        Self::note(unsafe { System.alloc(layout) }, layout.size())
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        Self::note(unsafe { System.alloc_zeroed(layout) }, layout.size())
    }

    unsafe fn dealloc(&self, pointer: *mut u8, layout: Layout) {
        // SAFETY: `pointer` came from this allocator, i.e. from `System`, with `layout`.
        unsafe { System.dealloc(pointer, layout) }
    }

    unsafe fn realloc(&self, pointer: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as for `dealloc`; the caller upholds `realloc`'s contract on `new_size`.
        Self::note(
            unsafe { System.realloc(pointer, layout, new_size) },
            new_size,
        )
    }
}

#[global_allocator]
static ALLOCATOR: Reporting = Reporting;

/// Bytes of the last allocation that failed since the module started, or `undefined` when none
/// has. Call it after a `RuntimeError` to tell an out-of-memory abort from a crash.
#[wasm_bindgen(js_name = failedAllocation)]
pub fn failed_allocation() -> Option<f64> {
    match FAILED_BYTES.load(Ordering::Relaxed) {
        0 => None,
        bytes => Some(bytes as f64),
    }
}

/// Size of the module's linear memory in bytes (it only ever grows).
#[wasm_bindgen(js_name = memoryBytes)]
pub fn memory_bytes() -> f64 {
    core::arch::wasm32::memory_size(0) as f64 * 65536.0
}
