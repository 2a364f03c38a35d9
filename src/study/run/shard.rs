//! [`Shard`]: the `i`-th of `n` parts of a run's items, for array jobs on a cluster.

use crate::error::{Error, Result};

/// The `index`-th of `count` parts of a run's items (`0 <= index < count`): item `k` of the
/// list sorted by its key goes to part `k mod count`. Disjoint, covering, balanced to one
/// item, and the same on every machine that sees the same list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which part, from 0.
    pub index: usize,
    /// How many parts.
    pub count: usize,
}

impl Shard {
    /// Parses `I/N` (`0 <= I < N`), as `--shard` takes it.
    ///
    /// # Errors
    /// [`Error::Parameter`] for anything else, with an example.
    pub fn parse(s: &str) -> Result<Shard> {
        let bad = || {
            Error::Parameter(format!(
                "--shard {s}: expected I/N with 0 <= I < N, e.g. 0/8 (Slurm: $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT)"
            ))
        };
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// `I/N`, as reports name the shard.
    pub fn label(&self) -> String {
        format!("{}/{}", self.index, self.count)
    }

    /// This part of `items`: sorted by `key`, items of equal keys kept once, then every
    /// `count`-th from `index`.
    pub fn select<T: Clone, K: Ord>(&self, items: &[T], key: impl Fn(&T) -> K) -> Vec<T> {
        let mut sorted: Vec<&T> = items.iter().collect();
        sorted.sort_by_key(|t| key(t));
        sorted.dedup_by(|a, b| key(a) == key(b));
        sorted
            .into_iter()
            .enumerate()
            .filter(|(k, _)| k % self.count.max(1) == self.index)
            .map(|(_, t)| t.clone())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn shards_are_disjoint_and_cover_the_list() {
        let files: Vec<PathBuf> = (0..23)
            .rev()
            .map(|k| PathBuf::from(format!("s{k:03}.ply")))
            .collect();
        for count in [1, 2, 5, 8, 30] {
            let part = |index| Shard { index, count }.select(&files, |p| p.clone());
            let mut all: Vec<PathBuf> = (0..count).flat_map(part).collect();
            assert_eq!(
                all.len(),
                files.len(),
                "{count} shards cover every item once"
            );
            all.sort();
            all.dedup();
            assert_eq!(all.len(), files.len());
            let sizes: Vec<usize> = (0..count).map(|i| part(i).len()).collect();
            assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1);
            // Stable: the same list in another order gives the same parts.
            let mut shuffled = files.clone();
            shuffled.rotate_left(7);
            for index in 0..count {
                let s = Shard { index, count };
                assert_eq!(
                    s.select(&files, |p| p.clone()),
                    s.select(&shuffled, |p| p.clone())
                );
            }
        }
    }

    #[test]
    fn shard_specs_are_checked() {
        assert_eq!(Shard::parse("2/8").unwrap(), Shard { index: 2, count: 8 });
        assert_eq!(Shard::parse("2/8").unwrap().label(), "2/8");
        for bad in ["8/8", "1", "a/2", "0/0", "-1/3"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }
}
