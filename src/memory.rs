//! Host memory accounting: a global allocator that counts live and peak
//! heap bytes, for the fuzz harness's allocation budget (`fuzz/`) and the
//! memory benchmark (`examples/memory.rs`), and the process's resident set
//! size. A binary opts in with
//! `#[global_allocator] static A: lambert::memory::Counting = lambert::memory::Counting;`;
//! the library itself never does.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

/// The system allocator, counting.
pub struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static CAP: AtomicUsize = AtomicUsize::new(usize::MAX);
static ON_CAP: OnceLock<fn()> = OnceLock::new();

/// Heap bytes allocated and not yet freed.
pub fn live() -> usize {
    LIVE.load(Relaxed)
}

/// The most `live` has been since the last `reset_peak`.
pub fn peak() -> usize {
    PEAK.load(Relaxed)
}

/// Starts a new peak from the bytes live now, and returns them.
pub fn reset_peak() -> usize {
    let live = LIVE.load(Relaxed);
    PEAK.store(live, Relaxed);
    live
}

/// Refuses any allocation that would take the live bytes past `bytes`,
/// after calling `exceeded` (which must not allocate); the allocation then
/// fails, which aborts the process. Set once.
pub fn set_cap(bytes: usize, exceeded: fn()) {
    let _ = ON_CAP.set(exceeded);
    CAP.store(bytes, Relaxed);
}

fn reserve(size: usize) -> bool {
    let live = LIVE.fetch_add(size, Relaxed) + size;
    if live > CAP.load(Relaxed) {
        LIVE.fetch_sub(size, Relaxed);
        if let Some(exceeded) = ON_CAP.get() {
            exceeded();
        }
        return false;
    }
    PEAK.fetch_max(live, Relaxed);
    true
}

/// `allocate`'s block of `layout` (the system's alloc or alloc_zeroed),
/// counted: null past the budget, and the count given back where the
/// system fails.
fn counted(layout: Layout, allocate: impl FnOnce() -> *mut u8) -> *mut u8 {
    if !reserve(layout.size()) {
        return std::ptr::null_mut();
    }
    let p = allocate();
    if p.is_null() {
        LIVE.fetch_sub(layout.size(), Relaxed);
    }
    p
}

// SAFETY: every call is forwarded to the system allocator; the counts are
// only bookkeeping.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        counted(layout, || unsafe { System.alloc(layout) })
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        counted(layout, || unsafe { System.alloc_zeroed(layout) })
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old && !reserve(new_size - old) {
            return std::ptr::null_mut();
        }
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            if new_size > old {
                LIVE.fetch_sub(new_size - old, Relaxed);
            }
        } else if new_size < old {
            LIVE.fetch_sub(old - new_size, Relaxed);
        }
        p
    }
}

/// The process's resident set size now and at its peak (VmRSS, VmHWM), in
/// bytes; None where /proc/self/status is not there (not Linux).
pub fn resident() -> Option<(u64, u64)> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let field = |name: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            .map(|kb| kb * 1024)
    };
    Some((field("VmRSS:")?, field("VmHWM:")?))
}

/// Resets the peak resident set size (VmHWM) to the current one, so that
/// phases can be measured one after another; false where the kernel does
/// not offer it (Linux's /proc/self/clear_refs, value 5).
pub fn reset_resident_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}
