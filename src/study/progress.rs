//! Progress of long work, reported through a callback: the library draws nothing (the command
//! line draws bars and spinners from these calls).

/// Receives the progress of long work. Every method has an empty default, so an
/// implementation overrides only what it shows. Called from worker threads, hence `Sync`.
pub trait Progress: Sync {
    /// A step of unknown length starts (building an atlas, meshing the mean).
    fn step_started(&self, _label: &str) {}
    /// The step `label` ended.
    fn step_finished(&self, _label: &str) {}
    /// `total` items of `label` (subjects, shapes) are about to be processed.
    fn items_started(&self, _label: &str, _total: usize) {}
    /// One item of `label` is done; `item` is its name.
    fn item_done(&self, _label: &str, _item: &str) {}
    /// Every item of `label` is done.
    fn items_finished(&self, _label: &str) {}
}

/// No progress output.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {}
