//! What a run costs in memory: the heap in use and its peak, counted by an allocator a
//! program installs ([`CountingAllocator`]; the command line does), and the peak of the
//! process's resident memory (`getrusage`). A cohort's scheduler request is written from
//! them (see docs/benchmarks.md).
//!
//! Units: bytes; the reports give MB (10⁶ bytes).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Heap bytes in use through [`CountingAllocator`].
static IN_USE: AtomicUsize = AtomicUsize::new(0);
/// The largest [`IN_USE`] since the process started or the last [`reset_heap_peak`].
static PEAK: AtomicUsize = AtomicUsize::new(0);

/// The system allocator, counting the bytes in use and their peak: install it with
/// `#[global_allocator] static A: CountingAllocator = CountingAllocator;` for the runs'
/// reports to give each subject's heap peak. Two relaxed atomic operations per allocation.
pub struct CountingAllocator;

fn grew(by: usize) {
    let now = IN_USE.fetch_add(by, Ordering::Relaxed) + by;
    if now > PEAK.load(Ordering::Relaxed) {
        PEAK.fetch_max(now, Ordering::Relaxed);
    }
}

fn shrank(by: usize) {
    IN_USE.fetch_sub(by, Ordering::Relaxed);
}

// SAFETY: every call goes to the system allocator with the caller's arguments unchanged; the
// counters are only arithmetic on the sizes.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is the system allocator's.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as `alloc`; `ptr` came from this allocator, hence from the system's.
        unsafe { System.dealloc(ptr, layout) };
        shrank(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as `dealloc`.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                grew(new_size - layout.size());
            } else {
                shrank(layout.size() - new_size);
            }
        }
        p
    }
}

/// Whether the program counts its heap ([`CountingAllocator`] installed): every program has
/// allocated by the time a run starts.
pub fn counting() -> bool {
    PEAK.load(Ordering::Relaxed) > 0
}

/// Starts a new peak: from now on, [`heap_peak_mb`] is the largest heap in use after this
/// call.
pub fn reset_heap_peak() {
    PEAK.store(IN_USE.load(Ordering::Relaxed), Ordering::Relaxed);
}

/// The largest heap in use since the last [`reset_heap_peak`] (or the start), in MB; `None`
/// when the program does not count its heap (no [`CountingAllocator`] installed).
pub fn heap_peak_mb() -> Option<f64> {
    counting().then(|| PEAK.load(Ordering::Relaxed) as f64 / 1e6)
}

/// The peak of the process's resident memory so far, in MB (`getrusage`; `None` where it
/// is not available).
pub fn resident_peak_mb() -> Option<f64> {
    peak_resident_bytes(libc::RUSAGE_SELF).map(|b| b / 1e6)
}

/// The largest resident memory (bytes) of the process (`who`: `RUSAGE_SELF`) or of its
/// waited-for children (`RUSAGE_CHILDREN`: a solver's), from `getrusage`; `None` where the
/// system does not say.
pub(crate) fn peak_resident_bytes(who: libc::c_int) -> Option<f64> {
    // SAFETY: rusage is plain data, all zeros a valid value; getrusage writes into it.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    let r = unsafe { libc::getrusage(who, &mut u) };
    // Linux gives kilobytes (KiB), macOS bytes.
    let bytes = if cfg!(target_os = "macos") {
        u.ru_maxrss as f64
    } else {
        u.ru_maxrss as f64 * 1024.0
    };
    (r == 0 && bytes > 0.0).then_some(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_counter_follows_allocations_and_their_peak() {
        // (The tests run with the system allocator: nothing counted until this one does.)
        assert!(!counting());
        assert_eq!(heap_peak_mb(), None);
        let mb = resident_peak_mb().unwrap();
        assert!(mb > 1.0 && mb < 1e6, "{mb} MB");
        let a = CountingAllocator;
        let layout = Layout::from_size_align(1 << 20, 8).unwrap();
        let before = IN_USE.load(Ordering::Relaxed);
        // SAFETY: a valid layout; the block is freed with it.
        unsafe {
            let p = a.alloc(layout);
            assert!(!p.is_null());
            assert_eq!(IN_USE.load(Ordering::Relaxed), before + (1 << 20));
            let q = a.realloc(p, layout, 3 << 20);
            assert!(!q.is_null());
            assert_eq!(IN_USE.load(Ordering::Relaxed), before + (3 << 20));
            assert!(PEAK.load(Ordering::Relaxed) >= before + (3 << 20));
            a.dealloc(q, Layout::from_size_align(3 << 20, 8).unwrap());
        }
        assert_eq!(IN_USE.load(Ordering::Relaxed), before);
        assert!(heap_peak_mb().unwrap() >= 3.0);
        reset_heap_peak();
        assert_eq!(PEAK.load(Ordering::Relaxed), before);
    }
}
