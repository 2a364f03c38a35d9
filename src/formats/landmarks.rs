//! Landmark files: Scalismo JSON (`[{"id": ..., "coordinates": [x, y(, z)]}, ...]`), `.pts`
//! (one point per line, optionally inside the `version: / n_points: / { ... }` frame of the
//! IBUG format), and CSV for a whole population (`shape,landmark,x,y[,z]` with coordinates,
//! or `shape,landmark,index` with point indices). Coordinates become the index of the
//! shape's nearest point ([`attach`]).

use crate::error::{Error, Result};
use crate::geometry::{Point, Shape, dist2};
use std::collections::BTreeMap;
use std::path::Path;

/// A landmark as given: a position, or the index of a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Landmark<const D: usize> {
    /// A position (snapped to the nearest point of the shape).
    At(Point<D>),
    /// The index of a point of the shape.
    Index(usize),
}

/// A landmark with its id (Scalismo's `id`, the CSV's `landmark` column, or the line's rank
/// from 1 in a `.pts` file). Landmarks of different shapes are paired by id.
pub type NamedLandmark<const D: usize> = (String, Landmark<D>);

/// Reads the landmarks of one shape from a Scalismo JSON or `.pts` file, ordered by id
/// ([`by_id`]).
pub fn read_landmarks<const D: usize>(path: &Path) -> Result<Vec<NamedLandmark<D>>> {
    let text = crate::formats::read_input_text(path)?;
    parse_landmarks::<D>(path, &text)
}

/// [`read_landmarks`] of a file's text (`path` only names the file in messages): no file is read.
pub fn parse_landmarks<const D: usize>(path: &Path, text: &str) -> Result<Vec<NamedLandmark<D>>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    if ext == "json" {
        let v: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| Error::parse(path, e.line(), format!("not JSON: {e}")))?;
        let items = v
            .as_array()
            .ok_or_else(|| Error::parse(path, 1, "expected a list of landmarks"))?;
        let v = items
            .iter()
            .enumerate()
            .map(|(k, it)| {
                // Scalismo names every landmark; a file without ids is paired by rank.
                let id = match it.get("id") {
                    None => (k + 1).to_string(),
                    Some(serde_json::Value::String(s)) => s.clone(),
                    Some(serde_json::Value::Number(n)) => n.to_string(),
                    Some(_) => {
                        return Err(Error::parse(
                            path,
                            0,
                            format!("landmark {k}: 'id' is neither text nor a number"),
                        ));
                    }
                };
                let c = it
                    .get("coordinates")
                    .and_then(|c| c.as_array())
                    .ok_or_else(|| {
                        Error::parse(path, 0, format!("landmark {k} has no 'coordinates'"))
                    })?;
                if c.len() != D {
                    return Err(Error::parse(
                        path,
                        0,
                        format!(
                            "landmark {k} has {} coordinates; the shapes are {D}D",
                            c.len()
                        ),
                    ));
                }
                let mut p = [0.0; D];
                for d in 0..D {
                    p[d] = c[d].as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                        Error::parse(
                            path,
                            0,
                            format!("landmark {k}: a coordinate is not a finite number"),
                        )
                    })?;
                }
                Ok((id, Landmark::At(p)))
            })
            .collect::<Result<Vec<_>>>()?;
        by_id(path, v)
    } else {
        let mut out = Vec::new();
        for (i, l) in text.lines().enumerate() {
            let l = l.trim();
            if l.is_empty()
                || l.starts_with('#')
                || l.starts_with("version")
                || l.starts_with("n_points")
                || l == "{"
                || l == "}"
            {
                continue;
            }
            let t: Vec<&str> = l.split_whitespace().collect();
            if t.len() != D {
                return Err(Error::parse(
                    path,
                    i + 1,
                    format!("expected {D} coordinates, got '{l}'"),
                ));
            }
            let mut p = [0.0; D];
            for d in 0..D {
                p[d] = t[d]
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        Error::parse(path, i + 1, format!("'{}' is not a finite number", t[d]))
                    })?;
            }
            out.push(((out.len() + 1).to_string(), Landmark::At(p)));
        }
        by_id(path, out)
    }
}

/// `landmarks` ordered by id, numeric ids in numeric order first, then the others in text
/// order (a total order, so the sort is well defined); a duplicated id is an error.
pub fn by_id<const D: usize>(
    path: &Path,
    mut landmarks: Vec<NamedLandmark<D>>,
) -> Result<Vec<NamedLandmark<D>>> {
    landmarks.sort_by_cached_key(|(id, _)| match id.parse::<i64>() {
        Ok(x) => (0u8, x, id.clone()),
        Err(_) => (1u8, 0, id.clone()),
    });
    if let Some(w) = landmarks.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(Error::parse(
            path,
            0,
            format!(
                "landmark id {:?} is given twice; each landmark needs its own id",
                w[0].0
            ),
        ));
    }
    Ok(landmarks)
}

/// Reads a population's landmarks from CSV, columns by name (others ignored): `shape`,
/// `landmark` (or `point`, `id`), then either coordinates `x`, `y`[, `z`] or a point index,
/// `index` (0-based) or `index1` (1-based, as R and Momocs number). Per shape name, the
/// landmarks ordered by their `landmark` column ([`by_id`]; an id twice in a shape is an
/// error).
pub fn read_landmarks_csv<const D: usize>(
    path: &Path,
) -> Result<BTreeMap<String, Vec<NamedLandmark<D>>>> {
    let text = crate::formats::read_input_text(path)?;
    parse_landmarks_csv::<D>(path, &text)
}

/// [`read_landmarks_csv`] of a file's text (`path` only names the file in messages): no file is read.
pub fn parse_landmarks_csv<const D: usize>(
    path: &Path,
    text: &str,
) -> Result<BTreeMap<String, Vec<NamedLandmark<D>>>> {
    let expected = "shape,landmark and x,y[,z], index (0-based) or index1 (1-based)";
    let t = super::csv_table::Table::parse(path, text, &Default::default())?;
    let shape = t.required(path, "shape", expected)?;
    let id = t.required(path, "point", expected)?;
    let index = match (t.column(path, "index")?, t.column(path, "index1")?) {
        (Some(c), None) => Some((c, 0)),
        (None, Some(c)) => Some((c, 1)),
        (Some(_), Some(_)) => {
            return Err(Error::parse(
                path,
                1,
                "both index and index1 columns: give one (index is 0-based, index1 1-based)",
            ));
        }
        (None, None) => None,
    };
    let axes = ["x", "y", "z"];
    let mut coords = [0usize; D];
    if index.is_none() {
        for (d, c) in coords.iter_mut().enumerate() {
            *c = t.required(path, axes[d], expected)?;
        }
    }
    let mut rows: BTreeMap<String, Vec<(String, Landmark<D>)>> = BTreeMap::new();
    for (ln, f) in &t.rows {
        let ln = *ln;
        let lm = if let Some((c, base)) = index {
            let i: usize = f[c]
                .parse()
                .ok()
                .filter(|&i: &usize| i >= base)
                .ok_or_else(|| {
                    Error::parse(
                        path,
                        ln,
                        format!("'{}' is not a point index ({}-based)", f[c], base),
                    )
                })?;
            Landmark::Index(i - base)
        } else {
            let mut p = [0.0; D];
            for d in 0..D {
                p[d] = f[coords[d]]
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        Error::parse(
                            path,
                            ln,
                            format!("'{}' is not a finite number", f[coords[d]]),
                        )
                    })?;
            }
            Landmark::At(p)
        };
        rows.entry(f[shape].to_string())
            .or_default()
            .push((f[id].to_string(), lm));
    }
    rows.into_iter()
        .map(|(k, v)| by_id(path, v).map(|v| (k, v)))
        .collect()
}

/// The farthest a landmark given by coordinates may lie from its shape's nearest point, as a
/// share of the diagonal of the shape's bounding box.
pub const MAX_LANDMARK_OFFSET: f64 = 0.1;

/// Sets `shape.landmarks` from `landmarks`: indices as given (checked), positions as the
/// index of the shape's nearest point (an error beyond [`MAX_LANDMARK_OFFSET`]). `source`
/// names the file in errors.
pub fn attach<const D: usize>(
    shape: &mut Shape<D>,
    landmarks: &[NamedLandmark<D>],
    source: &Path,
) -> Result<()> {
    let n = shape.points.len();
    let (lo, hi) = crate::geometry::bounding_box(&shape.points);
    let diagonal = dist2(lo, hi).sqrt();
    shape.landmarks = landmarks
        .iter()
        .map(|(k, l)| match *l {
            Landmark::Index(i) if i < n => Ok(i),
            Landmark::Index(i) => Err(Error::parse(
                source,
                0,
                format!(
                    "landmark {k} of {}: index {i} is out of range (the shape has {n} points)",
                    shape.name
                ),
            )),
            Landmark::At(p) => {
                let i = (0..n)
                    .min_by(|&a, &b| {
                        dist2(shape.points[a], p).total_cmp(&dist2(shape.points[b], p))
                    })
                    .unwrap_or(0);
                let d = dist2(shape.points[i], p).sqrt();
                if d > MAX_LANDMARK_OFFSET * diagonal {
                    return Err(Error::parse(
                        source,
                        0,
                        format!(
                            "landmark {k} of {} at {p:?} is far from the shape: {d:.3} from its \
                             nearest point, {:.0} % of the shape's size (at most {:.0} %); is \
                             the file for another shape or in other units?",
                            shape.name,
                            100.0 * d / diagonal,
                            100.0 * MAX_LANDMARK_OFFSET
                        ),
                    ));
                }
                Ok(i)
            }
        })
        .collect::<Result<Vec<_>>>()?;
    // Two landmarks on one point give the landmark term (and the pre-alignment) no direction.
    for (a, &i) in shape.landmarks.iter().enumerate() {
        if let Some(b) = shape.landmarks[a + 1..].iter().position(|&j| j == i) {
            return Err(Error::parse(
                source,
                0,
                format!(
                    "landmarks {} and {} of {} fall on the same point ({i}); give distinct points",
                    landmarks[a].0,
                    landmarks[a + 1 + b].0,
                    shape.name
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_pts_and_csv_landmarks() {
        let tmp = tempfile::Builder::new()
            .prefix("atlasmesh-lm-")
            .tempdir()
            .unwrap();
        let dir = tmp.path();
        let j = dir.join("a.json");
        std::fs::write(
            &j,
            r#"[{"id":"tip","coordinates":[1.0,2.0]},{"id":"b","coordinates":[3.0,-1.0]}]"#,
        )
        .unwrap();
        assert_eq!(
            read_landmarks::<2>(&j).unwrap(),
            vec![
                ("b".to_string(), Landmark::At([3.0, -1.0])),
                ("tip".to_string(), Landmark::At([1.0, 2.0]))
            ]
        );
        let dup = r#"[{"id":"a","coordinates":[1,2]},{"id":"a","coordinates":[3,4]}]"#;
        let e = parse_landmarks::<2>(&j, dup).unwrap_err().to_string();
        assert!(e.contains("\"a\" is given twice"), "{e}");
        let p = dir.join("a.pts");
        std::fs::write(&p, "version: 1\nn_points: 2\n{\n1 2\n3 -1\n}\n").unwrap();
        assert_eq!(read_landmarks::<2>(&p).unwrap().len(), 2);
        let c = dir.join("l.csv");
        std::fs::write(&c, "shape,landmark,index\ns1,1,7\ns1,0,3\ns2,0,4\n").unwrap();
        let m = read_landmarks_csv::<2>(&c).unwrap();
        let values = |v: &[NamedLandmark<2>]| v.iter().map(|x| x.1).collect::<Vec<_>>();
        assert_eq!(
            values(&m["s1"]),
            vec![Landmark::Index(3), Landmark::Index(7)]
        );
        let mut s = Shape::polyline("s1", vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], true);
        let e = attach(&mut s, &m["s1"], &c).unwrap_err().to_string();
        assert!(e.contains("out of range") && e.contains("l.csv"), "{e}");
        attach(&mut s, &[("a".into(), Landmark::At([0.9, 0.9]))], &c).unwrap();
        assert_eq!(s.landmarks, vec![2]);
        let two = [
            ("a".into(), Landmark::Index(1)),
            ("b".into(), Landmark::At([1.0, 0.1])),
        ];
        let e = attach(&mut s, &two, &c).unwrap_err().to_string();
        assert!(e.contains("a and b of s1 fall on the same point"), "{e}");
    }
}
