//! The folds of a cross-validation: a population's shapes in consecutive groups, each left
//! out of the model it is measured against (the k-fold of `loo --folds` and the
//! generalization of a large population).

use crate::error::{Error, Result};

/// The shapes `0..n` in `k` consecutive groups, the first `n % k` one shape larger than the
/// others (scikit-learn's `KFold` without shuffling).
///
/// # Errors
/// [`Error::Parameter`] for `k` below 2 or above `n`, or groups that leave fewer than 3 of the
/// `n` shapes to the atlas of another.
pub fn fold_groups(n: usize, k: usize) -> Result<Vec<Vec<usize>>> {
    if k < 2 || k > n {
        return Err(Error::Parameter(format!(
            "{k} folds: between 2 and the number of shapes ({n}) expected"
        )));
    }
    let (size, larger) = (n / k, n % k);
    let left = n - size - usize::from(larger > 0);
    if left < 3 {
        return Err(Error::Parameter(format!(
            "{k} folds of {n} shapes leave {left} shapes to an atlas; at least 3 are needed: \
             take more folds"
        )));
    }
    let mut start = 0;
    Ok((0..k)
        .map(|f| {
            let len = size + usize::from(f < larger);
            start += len;
            (start - len..start).collect()
        })
        .collect())
}
