//! CalculiX's ASCII result file (`.frd`): the nodal displacements of a solve. A result block
//! starts with a `-4  DISP` line, lists its components (`-5` lines) and then one `-1` line per
//! node: the node's number (10 columns after ` -1`) and its values in fields of 12 columns
//! (`-1.80389E-01`, written without a space between fields); ` -3` ends it.

use std::path::Path;

use crate::error::{Error, Result};

/// The displacements (mm, world axes of the deck) of the last `DISP` block of `text`, by node
/// number: entry `n - 1` is node `n`'s, NaN for a node the block does not list. `path` only
/// names the file in messages.
///
/// # Errors
/// [`Error::Parse`] (with the line) for no `DISP` block, a node number out of `1..=max_nodes`
/// or a value that is not a finite number.
pub fn parse_frd_displacements(path: &Path, text: &str, max_nodes: usize) -> Result<Vec<[f64; 3]>> {
    let mut last = None;
    let mut current: Option<Vec<[f64; 3]>> = None;
    for (k, line) in text.lines().enumerate() {
        let bad = |m: String| Error::parse(path, k + 1, m);
        if let Some(rest) = line.strip_prefix(" -4") {
            if let Some(done) = current.take() {
                last = Some(done);
            }
            if rest.trim_start().starts_with("DISP") {
                current = Some(Vec::new());
            }
        } else if line.starts_with(" -3") {
            if let Some(done) = current.take() {
                last = Some(done);
            }
        } else if let (Some(u), true) = (current.as_mut(), line.starts_with(" -1")) {
            let field = |a: usize, b: usize| line.get(a..b.min(line.len())).unwrap_or("").trim();
            let id: usize = field(3, 13)
                .parse()
                .map_err(|_| bad(format!("node number {:?}", field(3, 13))))?;
            if id == 0 || id > max_nodes {
                return Err(bad(format!("node {id}: the model has {max_nodes} nodes")));
            }
            let mut v = [0.0; 3];
            for (d, value) in v.iter_mut().enumerate() {
                let s = field(13 + 12 * d, 25 + 12 * d);
                *value = s
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad(format!("displacement {s:?} of node {id}")))?;
            }
            if u.len() < id {
                u.resize(id, [f64::NAN; 3]);
            }
            u[id - 1] = v;
        }
    }
    if let Some(done) = current {
        last = Some(done);
    }
    let mut u = last.ok_or_else(|| Error::parse(path, 0, "no displacement (DISP) block"))?;
    u.resize(max_nodes, [f64::NAN; 3]);
    Ok(u)
}

/// [`parse_frd_displacements`] of the file at `path`.
///
/// # Errors
/// Those of reading the file and of [`parse_frd_displacements`].
pub fn read_frd_displacements(path: &Path, max_nodes: usize) -> Result<Vec<[f64; 3]>> {
    parse_frd_displacements(path, &super::read_input_text(path)?, max_nodes)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FRD: &str = "    1C
    2C                             3                                     1
 -1         1 0.00000E+00 0.00000E+00 0.00000E+00
 -3
    1PSTEP                         1           1           1
 -4  DISP        4    1
 -5  D1          1    2    1    0
 -5  ALL         1    2    0    0    1ALL
 -1         1 3.86211E-02 4.12043E-02-1.80389E-01
 -1         3-1.00000E+00 2.00000E-03 0.00000E+00
 -3
 -4  STRESS      6    1
 -1         1 9.00000E+00 9.00000E+00 9.00000E+00
 -3
9999
";

    #[test]
    fn the_displacements_of_the_disp_block() {
        let u = parse_frd_displacements(Path::new("r.frd"), FRD, 3).unwrap();
        assert_eq!(u[0], [3.86211e-2, 4.12043e-2, -1.80389e-1]);
        assert!(u[1][0].is_nan());
        assert_eq!(u[2], [-1.0, 2e-3, 0.0]);
    }

    #[test]
    fn bad_results_are_refused_with_their_line() {
        for (text, says) in [
            ("    1C\n -3\n", "no displacement"),
            (
                " -4  DISP\n -1         7 1.0E+00 1.0E+00 1.0E+00\n",
                "node 7",
            ),
            (
                " -4  DISP\n -1         1 1.0E+00 nan 1.0E+00\n",
                "displacement",
            ),
            (" -4  DISP\n -1         1 1.0E+00\n", "displacement"),
            (" -4  DISP\n -1      abcd 1.0E+00\n", "node number"),
        ] {
            let e = parse_frd_displacements(Path::new("r.frd"), text, 3)
                .unwrap_err()
                .to_string();
            assert!(e.contains(says) && e.contains("r.frd"), "{e}");
        }
    }
}
