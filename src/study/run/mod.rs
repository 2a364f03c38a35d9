//! The run engine under every front end (command line, Python): a [`RunContext`] that owns
//! the atlas, the validated parameters and where the outputs go; one item loop
//! ([`run_items`]) of which the batch fit, the instances and the landmark posterior are
//! [`Job`]s; one [`Shard`]; one [`merge`] of reports.
//!
//! | file | what it does |
//! |---|---|
//! | `shard` | [`Shard`]: the `i`-th of `n` parts of the items |
//! | `context` | [`RunContext`]: the atlas, the parameters, the fitter and morph made once |
//! | `items` | [`run_items`]: the item loop, units' folders and records, resume |
//! | `merge` | [`merge`]: the reports of several shards joined |
//! | `memory` | [`CountingAllocator`]: the heap's peak per subject; the process's resident peak |

mod context;
mod items;
mod memory;
mod merge;
mod shard;

pub use context::{RunContext, RunPlace};
pub use items::{
    Job, Looping, Origin, Record, RunOutcome, UnitReport, Units, check_folders, run_items,
};
pub(crate) use memory::peak_resident_bytes;
pub use memory::{CountingAllocator, heap_peak_mb, reset_heap_peak, resident_peak_mb};
pub use merge::{RunReport, merge};
pub use shard::Shard;
