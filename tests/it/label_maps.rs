//! Label maps in: the 10 VerSe L1 vertebrae as NIfTI (RAS), NRRD and MetaImage (LPS) label
//! maps on oblique grids, written by nibabel and SimpleITK, whose true boundaries are the
//! source surfaces; TotalSegmentator's L1 fitted with an atlas of the VerSe vertebrae; and the
//! ways label maps go wrong.

use crate::common;
use atlasmesh::geometry::{ClosestPointIndex, Point, Shape};
use atlasmesh::study::{LabelReading, read_label_surface};
use std::path::{Path, PathBuf};

fn label_maps(data: &Path) -> Vec<PathBuf> {
    let dir = data.join("verse-L1-labelmaps-3d");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| atlasmesh::formats::is_image_file(p))
        .collect();
    v.sort();
    assert_eq!(v.len(), 10, "10 label maps in {}", dir.display());
    v
}

fn label(s: &str) -> LabelReading {
    LabelReading {
        choice: Some(s.parse().unwrap()),
        ..Default::default()
    }
}

/// The distances from every point of `a` to the surface `b`.
fn distances(a: &Shape<3>, b: &Shape<3>) -> Vec<f64> {
    let index = ClosestPointIndex::from_shape(b);
    let mut d: Vec<f64> = a
        .points
        .iter()
        .map(|p| index.closest(p).dist2.sqrt())
        .collect();
    d.sort_by(f64::total_cmp);
    d
}

fn quantile(d: &[f64], q: f64) -> f64 {
    d[((d.len() - 1) as f64 * q).round() as usize]
}

#[test]
fn each_label_surface_lies_on_its_true_surface_in_every_format_and_frame() {
    let Some(data) = common::data_dir("label surfaces") else {
        return;
    };
    for map in label_maps(&data) {
        let s = read_label_surface(&map, &label("20")).unwrap();
        let name = s.shape.name.clone();
        let truth = atlasmesh::formats::read_surface(
            &data.join(format!("verse-L1-vertebrae-3d/raw/{name}.ply")),
        )
        .unwrap();
        let voxel = s.spacing.iter().copied().fold(f64::INFINITY, f64::min);
        let out = distances(&s.shape, &truth);
        let back = distances(&truth, &s.shape);
        eprintln!(
            "{name}: {} points; to the truth median {:.3} p95 {:.3} mm, back median {:.3} p95 {:.3} mm (voxel {voxel} mm)",
            s.shape.points.len(),
            quantile(&out, 0.5),
            quantile(&out, 0.95),
            quantile(&back, 0.5),
            quantile(&back, 0.95)
        );
        for (what, d) in [("label to truth", &out), ("truth to label", &back)] {
            assert!(
                quantile(d, 0.5) <= 0.5 * voxel,
                "{name} {what}: median {}",
                quantile(d, 0.5)
            );
            assert!(
                quantile(d, 0.95) <= voxel,
                "{name} {what}: p95 {}",
                quantile(d, 0.95)
            );
        }
        assert!(!s.partial, "{name}: the vertebra is whole in its image");
        // A closed surface, oriented outwards (positive volume).
        assert!(atlasmesh::geometry::is_closed_surface(&s.shape), "{name}");
        assert!(atlasmesh::geometry::signed_volume(&s.shape) > 0.0, "{name}");
    }
}

#[test]
fn labels_are_chosen_by_number_several_at_once_or_by_name() {
    let Some(data) = common::data_dir("label choice") else {
        return;
    };
    let map = data.join("verse-L1-labelmaps-3d/sub-verse013_segment_20.nrrd");
    let l20 = read_label_surface(&map, &label("20")).unwrap();
    let l19 = read_label_surface(&map, &label("19")).unwrap();
    // The neighbours are other vertebrae, shrunk: smaller and elsewhere.
    let centre = |s: &Shape<3>| atlasmesh::geometry::centroid(&s.points);
    let gap = atlasmesh::geometry::dist2(centre(&l20.shape), centre(&l19.shape)).sqrt();
    assert!(
        gap > 10.0,
        "label 19 is not label 20: centres {gap} mm apart"
    );
    assert!(l19.voxels < l20.voxels);
    // Three labels that do not touch: the largest kept, the two others dropped as islands.
    let all = read_label_surface(&map, &label("19,20,21")).unwrap();
    assert_eq!(all.voxels, l20.voxels.max(l19.voxels));
    assert!(
        all.warnings
            .iter()
            .any(|w| w.contains("2 floating islands")),
        "{:?}",
        all.warnings
    );
    // By name from a table.
    let dir = common::temp_dir("label-table");
    let table = dir.join("names.csv");
    std::fs::write(
        &table,
        "label,name\n19,vertebrae_T12\n20,vertebrae_L1\n21,vertebrae_L2\n",
    )
    .unwrap();
    let by_name = LabelReading::new(Some("vertebrae_L1".parse().unwrap()), Some(&table)).unwrap();
    let named = read_label_surface(&map, &by_name).unwrap();
    assert_eq!(named.shape.points, l20.shape.points);
    // An absent label lists those present, with their names.
    let e = read_label_surface(&map, &label("7"))
        .unwrap_err()
        .to_string();
    for want in [
        "sub-verse013_segment_20.nrrd",
        "label 7",
        "19 (",
        "20 (",
        "21 (",
    ] {
        assert!(e.contains(want), "{e}");
    }
    let with_names = LabelReading::new(Some("7".parse().unwrap()), Some(&table)).unwrap();
    let e = read_label_surface(&map, &with_names)
        .unwrap_err()
        .to_string();
    assert!(e.contains("vertebrae_L1"), "{e}");
    let unknown = LabelReading::new(Some("femur_left".parse().unwrap()), Some(&table)).unwrap();
    let e = read_label_surface(&map, &unknown).unwrap_err().to_string();
    assert!(
        e.contains("femur_left") && e.contains("vertebrae_T12"),
        "{e}"
    );
    // No label given: the message asks for one.
    let e = read_label_surface(&map, &LabelReading::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("--label"), "{e}");
    // TotalSegmentator's T12 is cut by the CT's last slice: an open, partial surface.
    let seg = data.join("totalseg-example-ct-3d/example_seg.nii.gz");
    let t12 = read_label_surface(&seg, &label("32")).unwrap();
    assert!(t12.partial);
    assert!(!atlasmesh::geometry::is_closed_surface(&t12.shape));
    assert!(
        t12.warnings.iter().any(|w| w.contains("k = last")),
        "{:?}",
        t12.warnings
    );
    let l1 = read_label_surface(&seg, &label("31")).unwrap();
    assert!(!l1.partial && atlasmesh::geometry::is_closed_surface(&l1.shape));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn convert_writes_the_label_surface_that_meshio_reads_back() {
    let Some(data) = common::data_dir("convert label map") else {
        return;
    };
    let dir = common::temp_dir("convert-label");
    let map = data.join("verse-L1-labelmaps-3d/sub-verse016_segment_20.mha");
    let mut files = Vec::new();
    for ext in ["ply", "stl", "vtk"] {
        let out = dir.join(format!("l1.{ext}"));
        let o = common::atlasmesh(&[
            "convert".into(),
            map.display().to_string(),
            out.display().to_string(),
            "--label".into(),
            "20".into(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        files.push(out);
    }
    let s = read_label_surface(&map, &label("20")).unwrap();
    if let Some(read) = common::meshio_meshes(&files) {
        for ((points, cells), f) in read.iter().zip(&files) {
            assert_eq!(cells.len(), s.shape.facets.len(), "{}", f.display());
            // STL repeats corners per triangle; the others keep the points.
            if !f.display().to_string().ends_with(".stl") {
                assert_eq!(points.len(), s.shape.points.len(), "{}", f.display());
                for (p, q) in points.iter().zip(&s.shape.points) {
                    assert!(
                        (0..3).all(|k| (p[k] - q[k]).abs() < 1e-6),
                        "{}",
                        f.display()
                    );
                }
            }
        }
    }
    // --label on a mesh is refused, and a label map without --label.
    let o = common::atlasmesh(&[
        "convert".into(),
        map.display().to_string(),
        dir.join("x.ply").display().to_string(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--label"));
    assert!(!dir.join("x.ply").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A NIfTI-1 file (single, little-endian) of `dims` voxels of NIfTI type `datatype` from
/// `data`, voxel sizes `pixdim`, the sform its diagonal (code 1) when `sform`.
fn nifti1(
    dims: [i16; 3],
    datatype: i16,
    bitpix: i16,
    pixdim: [f32; 3],
    sform: bool,
    data: &[u8],
) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let dim = [3i16, dims[0], dims[1], dims[2], 1, 1, 1, 1];
    for (k, d) in dim.iter().enumerate() {
        h[40 + 2 * k..42 + 2 * k].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&datatype.to_le_bytes());
    h[72..74].copy_from_slice(&bitpix.to_le_bytes());
    let pd = [1.0f32, pixdim[0], pixdim[1], pixdim[2]];
    for (k, v) in pd.iter().enumerate() {
        h[76 + 4 * k..80 + 4 * k].copy_from_slice(&v.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    if sform {
        h[254..256].copy_from_slice(&1i16.to_le_bytes());
        for (r, v) in pixdim.iter().enumerate() {
            let at = 280 + 16 * r + 4 * r;
            h[at..at + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend_from_slice(data);
    h
}

/// `b` compressed by gzip.
fn gzip(b: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(b).unwrap();
    e.finish().unwrap()
}

fn zlib(b: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(b).unwrap();
    e.finish().unwrap()
}

/// An image as another program reads it: its voxels (x fastest) and its affine (NIfTI only).
type TheirImage = (Vec<f64>, Vec<Vec<f64>>);

/// nibabel's (`.nii*`) or SimpleITK's (other) voxels of each file of `files`, in x-fastest
/// order, and nibabel's affine (RAS) for NIfTI; `None` without the Python tools.
fn voxels_by_python(files: &[PathBuf]) -> Option<Vec<TheirImage>> {
    let py = common::python()?;
    let script = r#"
import sys, json
import numpy as np, nibabel as nib, SimpleITK as sitk
out = []
for f in sys.argv[1:]:
    if ".nii" in f:
        img = nib.load(f)
        v = np.asarray(img.dataobj).reshape(img.shape[:3], order="F")
        out.append([v.flatten(order="F").astype(float).tolist(), img.affine[:3].tolist()])
    else:
        v = sitk.GetArrayFromImage(sitk.ReadImage(f))
        out.append([v.flatten().astype(float).tolist(), []])
print(json.dumps(out))
"#;
    let o = common::run(
        std::process::Command::new(py)
            .arg("-c")
            .arg(script)
            .args(files),
        common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    Some(serde_json::from_slice(&o.stdout).unwrap())
}

/// Voxels come from where the header says they start, and the header's sizes are checked
/// against the data. Odd but valid files read the voxels nibabel and SimpleITK read: a NIfTI
/// with a byte after its volume (plain and gzip), one holding a second volume its
/// `dim[0] = 3` does not describe, one whose bitpix disagrees with its datatype (read by the
/// datatype, with a note), an NRRD and a MetaImage with a line end after their
/// voxels, a detached NRRD whose voxels end its data file (`byte skip: -1`). Refused, naming
/// the cause: NRRD and MetaImage data a slice or more longer than their sizes (SimpleITK reads
/// the first slices of it), a `vox_offset` inside the header, a qform quaternion that is not a
/// rotation (nibabel refuses it), `dim[0]` outside 1..7, a negative size, a detached data
/// file linked from outside the header's folder, ASCII values the type cannot hold (300 as
/// `uchar`, 20.7 as an integer: they were saturated and truncated).
#[test]
fn voxels_come_from_where_the_header_says_and_its_sizes_fit_the_data() {
    let dir = common::temp_dir("image-placement");
    let good = nifti1([8, 8, 8], 2, 8, [1.0, 1.0, 2.0], true, &block());
    let nrrd = |sizes: &str, extra: &str| {
        format!("NRRD0004\ntype: uchar\ndimension: 3\nsizes: {sizes}\nencoding: raw\n{extra}\n")
            .into_bytes()
    };
    let mhd = b"ObjectType = Image\nNDims = 3\nDimSize = 8 8 8\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
    let with = |head: &[u8], tail: &[u8]| [head, &block(), tail].concat();
    let mut trailing = good.clone();
    trailing.push(7);
    let two_volumes = [&good[..], &[9u8; 512]].concat();
    std::fs::write(dir.join("d.raw"), [&b"0123456789"[..], &block()].concat()).unwrap();
    let valid: Vec<(&str, Vec<u8>)> = vec![
        ("trailing.nii", trailing.clone()),
        ("trailing.nii.gz", gzip(&trailing)),
        ("two-volumes.nii", two_volumes),
        (
            "bitpix.nii",
            nifti1([8, 8, 8], 2, 16, [1.0, 1.0, 2.0], true, &block()),
        ),
        ("newline.nrrd", with(&nrrd("8 8 8", ""), b"\n")),
        ("newline.mhd", with(mhd, b"\n")),
        (
            "end.nhdr",
            nrrd("8 8 8", "byte skip: -1\ndata file: d.raw\n"),
        ),
    ];
    let mut files = Vec::new();
    for (name, bytes) in &valid {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let file = atlasmesh::formats::read_image(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        // A bitpix that disagrees with the datatype is read past with a note naming both.
        let noted = file
            .notes
            .iter()
            .any(|n| n.contains("bitpix 16 disagrees with datatype 2 (8 bits)"));
        assert_eq!(noted, *name == "bitpix.nii", "{name}: {:?}", file.notes);
        let image = file.image;
        assert_eq!(image.dims, [8, 8, 8], "{name}");
        assert!(
            image.data == block(),
            "{name}: not the voxels of the header's volume"
        );
        files.push(path);
    }
    if let Some(theirs) = voxels_by_python(&files) {
        let want: Vec<f64> = block().iter().map(|&v| f64::from(v)).collect();
        for (k, (v, affine)) in theirs.iter().enumerate() {
            assert_eq!(
                v, &want,
                "{}: other voxels than nibabel's or SimpleITK's",
                valid[k].0
            );
            if !affine.is_empty() {
                let ours = atlasmesh::formats::read_image(&files[k])
                    .unwrap()
                    .image
                    .affine;
                for (r, row) in affine.iter().enumerate() {
                    for (c, x) in row.iter().enumerate() {
                        assert!(
                            (ours[r][c] - x).abs() <= 1e-9,
                            "{}: affine {ours:?}",
                            valid[k].0
                        );
                    }
                }
            }
        }
    }
    let mut inside = good.clone();
    inside[108..112].copy_from_slice(&100f32.to_le_bytes());
    // The qform alone (sform code 0), its (b, c, d) = (1, 1, 1).
    let mut quaternion = nifti1([8, 8, 8], 2, 8, [1.0; 3], false, &block());
    quaternion[252..254].copy_from_slice(&1i16.to_le_bytes());
    for k in 0..3 {
        quaternion[256 + 4 * k..260 + 4 * k].copy_from_slice(&1f32.to_le_bytes());
    }
    let mut nine = good.clone();
    nine[40..42].copy_from_slice(&9i16.to_le_bytes());
    // A detached data file that is a link out of the header's folder.
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::write(dir.join("outside.raw"), block()).unwrap();
    std::os::unix::fs::symlink("../outside.raw", dir.join("sub/link.raw")).unwrap();
    let ascii = |data: &str| {
        format!("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 1 1\nencoding: ascii\n\n{data}\n")
            .into_bytes()
    };
    let mut negative = good.clone();
    negative[46..48].copy_from_slice(&(-2i16).to_le_bytes());
    let refused: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "sizes-short.nrrd",
            with(&nrrd("8 8 7", ""), b""),
            "announces 448 bytes of voxels, the data holds 512",
        ),
        (
            "sizes-short.nrrd.gz.nrrd",
            [
                &b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 8 8 6\nencoding: gzip\n\n"[..],
                &gzip(&block()),
            ]
            .concat(),
            "announces 384 bytes of voxels",
        ),
        (
            "sizes-short.mhd",
            with(
                &String::from_utf8_lossy(mhd)
                    .replace("8 8 8", "8 8 7")
                    .into_bytes(),
                b"",
            ),
            "the data holds 512",
        ),
        (
            "inside.nii",
            inside,
            "vox_offset 100 lies inside the header",
        ),
        ("quaternion.nii", quaternion, "is not a rotation"),
        ("nine.nii", nine, "dim[0] = 9"),
        ("negative.nii", negative, "dim[3] = -2"),
        (
            "sub/link.nhdr",
            nrrd("8 8 8", "data file: link.raw\n"),
            "outside the header's folder",
        ),
        (
            "ascii-range.nrrd",
            ascii("300 1"),
            "\"300\" is out of the range",
        ),
        (
            "ascii-fraction.nrrd",
            ascii("20.7 1"),
            "\"20.7\" is not a whole number",
        ),
        // 1 GiB of voxels announced by 1 MB of zeros compressed (1 kB): refused before any
        // inflating (the input limit, 2 GiB, lets its size through).
        (
            "bomb.nii.gz",
            gzip(&nifti1([1024; 3], 2, 8, [1.0; 3], true, &[0u8; 1 << 20])),
            "decompression bomb",
        ),
        // The same through NRRD's gzip and MetaImage's zlib encodings.
        (
            "bomb.nrrd",
            [
                &b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1024 1024 1024\nencoding: gzip\n\n"[..],
                &gzip(&[0u8; 1 << 20]),
            ]
            .concat(),
            "decompression bomb",
        ),
        (
            "bomb.mha",
            [
                &b"ObjectType = Image\nNDims = 3\nDimSize = 1024 1024 1024\nElementType = MET_UCHAR\nCompressedData = True\nElementDataFile = LOCAL\n"[..],
                &zlib(&[0u8; 1 << 20]),
            ]
            .concat(),
            "decompression bomb",
        ),
    ];
    for (name, bytes, want) in &refused {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let e = match atlasmesh::formats::read_image(&path) {
            Ok(_) => panic!("{name}: read, should be refused"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(name) && e.contains(want), "{name}: {e}");
    }
    // The bomb through the command line, in 1 GiB of address space: as a label map to
    // `convert` and as a CT to `materials`, refused with its cause and nothing written.
    let mesh = dir.join("block.vtu");
    atlasmesh::formats::write_vtu(&mesh, &atlasmesh::mesh::FeMesh::block(2), None).unwrap();
    let bomb = dir.join("bomb.nii.gz").display().to_string();
    let (ply, out) = (dir.join("bomb.ply"), dir.join("materials-out"));
    for args in [
        vec!["convert", &bomb, ply.to_str().unwrap(), "--label", "1"],
        vec![
            "materials",
            "--mesh",
            mesh.to_str().unwrap(),
            "--ct",
            &bomb,
            "--out",
            out.to_str().unwrap(),
        ],
    ] {
        let o = crate::hostile_outputs::in_1gib(&args);
        crate::bad_input::fails(&o, 2, &["bomb.nii.gz", "decompression bomb"]);
    }
    assert!(!ply.exists() && !out.exists());
}

/// Labels are whole numbers compared as integers: an int64 label 2⁵³ + 1 beside a background
/// of 2⁵³ (one number in `f64`) is told apart; a float map whose voxels are 1.0000001 is
/// refused as no label numbers. Label tables: a byte-order mark does not hide the first
/// row, a number or a name given twice is refused naming both lines, names are shown cut and
/// without control characters.
#[test]
fn labels_are_integers_and_label_tables_say_each_name_once() {
    let dir = common::temp_dir("label-numbers");
    let (big, background) = ((1i64 << 53) + 1, 1i64 << 53);
    let voxels: Vec<u8> = block()
        .iter()
        .flat_map(|&v| if v == 1 { big } else { background }.to_le_bytes())
        .collect();
    let path = dir.join("int64.nii");
    std::fs::write(&path, nifti1([8, 8, 8], 1024, 64, [1.0; 3], true, &voxels)).unwrap();
    let s = read_label_surface(&path, &label(&big.to_string())).unwrap();
    let (lo, hi) = atlasmesh::geometry::bounding_box(&s.shape.points);
    for k in 0..3 {
        assert!(
            (lo[k] - 0.5).abs() <= 0.5 && (hi[k] - 6.5).abs() <= 0.5,
            "the label's surface is not the block's: {lo:?} {hi:?}"
        );
    }
    let floats: Vec<u8> = block()
        .iter()
        .flat_map(|&v| if v == 1 { 1.000_000_1f32 } else { 0.0 }.to_le_bytes())
        .collect();
    let path = dir.join("float.nii");
    std::fs::write(&path, nifti1([8, 8, 8], 16, 32, [1.0; 3], true, &floats)).unwrap();
    let e = read_label_surface(&path, &label("1"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("float.nii") && e.contains("not a whole number"),
        "{e}"
    );
    // Label tables.
    let table = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        atlasmesh::study::read_label_table(&p)
    };
    let t = table("bom.csv", "\u{feff}1,vertebrae_L1\n2,vertebrae_L2\n").unwrap();
    assert_eq!(t.name(1), Some("vertebrae_L1"));
    for (name, text, want) in [
        (
            "number.csv",
            "label,name\n1,a\n2,b\n1,c\n",
            "label 1 is named twice, on lines 2 and 4",
        ),
        (
            "name.csv",
            "1,Femur\n2,tibia\n3,femur\n",
            "given twice, on lines 1 and 3",
        ),
    ] {
        let e = table(name, text).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains(want), "{name}: {e}");
    }
    let long = format!("1,\u{1b}[31m{}\n", "x".repeat(100_000));
    let t = table("long.csv", &long).unwrap();
    let reading = LabelReading {
        choice: Some("nope".parse().unwrap()),
        table: t,
    };
    let e = read_label_surface(&dir.join("int64.nii"), &reading)
        .unwrap_err()
        .to_string();
    assert!(
        e.len() < 1000 && !e.contains('\u{1b}'),
        "{} bytes: {:?}",
        e.len(),
        &e[..200]
    );
}

/// Writes DICOM series with pydicom (a good one of 4 slices of 6 × 8 int16 pixels with a
/// structured report beside it, and bad ones), prints SimpleITK's reading of the good one.
const DICOM_SERIES: &str = r#"
import sys, os, numpy as np, pydicom
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.uid import ExplicitVRLittleEndian, generate_uid, CTImageStorage
out = sys.argv[1]
series = generate_uid()
def slice_ds(k, **kw):
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = CTImageStorage
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset(); ds.file_meta = meta
    ds.SOPClassUID = CTImageStorage; ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
    ds.Modality = "CT"; ds.SeriesInstanceUID = series; ds.StudyInstanceUID = series
    ds.PatientName = "test"; ds.InstanceNumber = k + 1
    ds.ImagePositionPatient = [-10.0, -20.0, 5.0 + 2.0 * k]
    ds.ImageOrientationPatient = kw.get("orientation", [1, 0, 0, 0, 1, 0])
    ds.PixelSpacing = [0.5, 0.75]
    ds.Rows, ds.Columns = 8, 6
    ds.SamplesPerPixel = 1; ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated = 16; ds.BitsStored = 16; ds.HighBit = 15; ds.PixelRepresentation = 1
    ds.RescaleSlope = kw.get("slope", "1"); ds.RescaleIntercept = kw.get("intercept", "-1024")
    px = (np.arange(48, dtype=np.int16).reshape(8, 6) * 10 + 100 * k).astype(np.int16)
    ds.PixelData = px.tobytes()
    return ds
def write(folder, n, **kw):
    os.makedirs(folder, exist_ok=True)
    for k in range(n):
        slice_ds(k, **kw).save_as(os.path.join(folder, f"s{k:02d}.dcm"), enforce_file_format=True)
write(out + "/good", 4)
# a structured report beside the series: no pixel data
meta = FileMetaDataset(); meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.88.67"
meta.MediaStorageSOPInstanceUID = generate_uid(); meta.TransferSyntaxUID = ExplicitVRLittleEndian
sr = Dataset(); sr.file_meta = meta; sr.SOPClassUID = meta.MediaStorageSOPClassUID
sr.SOPInstanceUID = meta.MediaStorageSOPInstanceUID; sr.Modality = "SR"; sr.SeriesInstanceUID = generate_uid()
sr.save_as(out + "/good/dose_report.dcm", enforce_file_format=True)
write(out + "/slope-nan", 4, slope="NaN")
write(out + "/intercept-nan", 4, intercept="NaN")
write(out + "/slope-zero", 1, slope="0")
write(out + "/orientation-long", 4, orientation=[1, 1, 1, 0, 1, 0])
write(out + "/orientation-zero", 4, orientation=[0, 0, 0, 0, 1, 0])
write(out + "/orientation-parallel", 4, orientation=[1, 0, 0, 1, 0, 0])
# SimpleITK's reading of the good series (the report left aside by its series reader)
import SimpleITK as sitk, json
r = sitk.ImageSeriesReader(); r.SetFileNames([out + f"/good/s{k:02d}.dcm" for k in range(4)])
img = r.Execute()
a = sitk.GetArrayFromImage(img).astype(float)  # z, y, x
print(json.dumps({"values": a.flatten().tolist(), "origin": list(img.GetOrigin()), "spacing": list(img.GetSpacing()), "direction": list(img.GetDirection())}))
"#;

/// The numbers of a JSON array.
fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

/// DICOM series: an object without pixel data beside the slices (a dose report) is passed
/// over with a note, and the series reads the HU and the geometry SimpleITK reads; a rescale
/// slope or intercept that is NaN, a slope of 0, and an orientation that is not two
/// orthogonal unit directions (too long, zero, parallel) are refused, naming the file and the
/// cause. Needs pydicom and SimpleITK (`ATLASMESH_PYTHON`).
#[test]
fn dicom_series_refuse_bad_rescales_and_orientations_and_skip_reports() {
    let Some(py) = common::python() else {
        return;
    };
    let dir = common::temp_dir("dicom-checks");
    let o = common::run(
        std::process::Command::new(py)
            .arg("-W")
            .arg("ignore")
            .arg("-c")
            .arg(DICOM_SERIES)
            .arg(&*dir),
        common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let theirs: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let file = atlasmesh::formats::read_image(&dir.join("good")).unwrap();
    assert!(
        file.notes.len() == 1
            && file.notes[0].contains("dose_report.dcm")
            && file.notes[0].contains("without pixel data"),
        "{:?}",
        file.notes
    );
    let image = file.image;
    assert_eq!(image.dims, [6, 8, 4]);
    let values = numbers(&theirs["values"]);
    for (i, v) in values.iter().enumerate() {
        assert!(
            (image.value(i) - v).abs() <= 1e-9,
            "voxel {i}: {} against {v}",
            image.value(i)
        );
    }
    // SimpleITK's origin and spacing are LPS; the image's affine is RAS.
    let origin = numbers(&theirs["origin"]);
    let spacing = numbers(&theirs["spacing"]);
    let a = image.affine;
    for r in 0..3 {
        let sign = if r < 2 { -1.0 } else { 1.0 };
        assert!(
            (a[r][3] - sign * origin[r]).abs() <= 1e-9,
            "origin {a:?} against {origin:?}"
        );
        assert!(
            (a[r][r].abs() - spacing[r]).abs() <= 1e-9,
            "spacing {a:?} against {spacing:?}"
        );
    }
    for (folder, want) in [
        ("slope-nan", "RescaleSlope \"NaN\" is not a finite number"),
        (
            "intercept-nan",
            "RescaleIntercept \"NaN\" is not a finite number",
        ),
        ("slope-zero", "RescaleSlope 0"),
        ("orientation-long", "is not two orthogonal unit directions"),
        ("orientation-zero", "is not two orthogonal unit directions"),
        ("orientation-parallel", "cosine 1.0000"),
    ] {
        let e = atlasmesh::formats::read_image(&dir.join(folder))
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(e.contains(folder) && e.contains(want), "{folder}: {e}");
    }
}

/// A DICOM file's declared lengths are checked before it is parsed: a slice whose Pixel Data
/// declares 1.97 GB in a 640-byte file (the fuzzer's finding; the parser reserved and zeroed
/// the length before reading), a value of a binary VR whose length is not a whole number of
/// values (the parser lost its place and read 1.3 GB from a text value), and a slice
/// announcing 65535 × 65535 pixels, are refused with
/// their cause, by the reader and by `materials` in 1 GiB of address space, nothing written;
/// the slice they were made from reads.
#[test]
fn dicom_lengths_and_sizes_beyond_the_file_are_refused_before_parsing() {
    let dir = common::temp_dir("dicom-lengths");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let seed = std::fs::read(root.join("fuzz/seeds/dicom/ct_int16.dcm")).unwrap();
    let declared =
        std::fs::read(root.join("fuzz/regressions/dicom/oom-declared-length-pixel-data")).unwrap();
    // SamplesPerPixel as UL of 2 bytes: the parser read the next bytes as a header declaring
    // 1.3 GB.
    let desync = std::fs::read(
        root.join("fuzz/regressions/dicom/timeout-desynchronized-binary-value-length"),
    )
    .unwrap();
    // Rows and Columns (0028,0010) and (0028,0011), US, set to 65535.
    let mut huge = seed.clone();
    for element in [0x10u8, 0x11] {
        let tag = [0x28, 0x00, element, 0x00, b'U', b'S', 2, 0];
        let at = huge.windows(8).position(|w| w == tag).unwrap() + 8;
        huge[at..at + 2].copy_from_slice(&[0xFF, 0xFF]);
    }
    let mesh = dir.join("block.vtu");
    atlasmesh::formats::write_vtu(&mesh, &atlasmesh::mesh::FeMesh::block(2), None).unwrap();
    for (name, bytes, want) in [
        ("seed", seed, ""),
        ("declared", declared, "declares 1968046082 bytes"),
        ("huge", huge, "65535 × 65535 pixels of 16 bits"),
        ("desync", desync, "not a whole number of UL values"),
    ] {
        let folder = dir.join(name);
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::write(folder.join("slice.dcm"), &bytes).unwrap();
        let read = atlasmesh::formats::read_image(&folder);
        if want.is_empty() {
            assert_eq!(read.unwrap().image.dims[2], 1, "{name}");
            continue;
        }
        let e = read.map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("slice.dcm") && e.contains(want), "{name}: {e}");
        let out = dir.join(format!("{name}-out"));
        let o = crate::hostile_outputs::in_1gib(&[
            "materials",
            "--mesh",
            mesh.to_str().unwrap(),
            "--ct",
            folder.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        crate::bad_input::fails(&o, 2, &["slice.dcm", want]);
        assert!(!out.exists(), "{name}: an output folder was left");
    }
}

/// Messages about images stay short and on their lines: a 1 MB NRRD header line, and a
/// MetaImage header followed by binary, are cut in the message; a label map and a mesh whose
/// names hold a line break and `error: ...` or an escape code cannot start a line of
/// `convert`'s or `materials`' output of their own.
#[test]
fn image_messages_are_cut_and_keep_to_their_lines() {
    let dir = common::temp_dir("image-messages");
    let long = dir.join("long.nrrd");
    let mut bytes = b"NRRD0004\ntype: uchar\n".to_vec();
    bytes.extend(std::iter::repeat_n(b'x', 1 << 20));
    bytes.extend(b"\n\n");
    std::fs::write(&long, &bytes).unwrap();
    let binary = dir.join("binary.mhd");
    let mut bytes = b"ObjectType = Image\nNDims = 3\n".to_vec();
    bytes.extend((0..14_000u32).map(|i| (i % 200 + 32) as u8));
    std::fs::write(&binary, &bytes).unwrap();
    for path in [&long, &binary] {
        let e = atlasmesh::formats::read_image(path)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(e.len() < 600, "{} bytes: {}", e.len(), &e[..600]);
    }
    // Names forging lines.
    let good = nifti1([8, 8, 8], 2, 8, [1.0; 3], true, &block());
    let forged = dir.join("a\nerror: forged\u{1b}[2J.nii");
    std::fs::write(&forged, &good).unwrap();
    let ct = dir.join("ct\nwarning: forged.nii");
    let hu: Vec<u8> = (0..512).flat_map(|_| 700i16.to_le_bytes()).collect();
    std::fs::write(&ct, nifti1([8, 8, 8], 4, 16, [1.0; 3], true, &hu)).unwrap();
    let mesh = dir.join("m\nerror: forged.vtu");
    let mut block_mesh = atlasmesh::mesh::FeMesh::block(2);
    for p in &mut block_mesh.nodes {
        for c in p.iter_mut() {
            *c = 2.0 + 1.5 * *c;
        }
    }
    atlasmesh::formats::write_vtu(&mesh, &block_mesh, None).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    for args in [
        vec![
            "convert".to_string(),
            s(&forged),
            s(&dir.join("o.ply")),
            "--label".into(),
            "1".into(),
        ],
        vec![
            "convert".to_string(),
            s(&forged),
            s(&dir.join("o.ply")),
            "--label".into(),
            "9".into(),
        ],
        vec![
            "materials".to_string(),
            "--mesh".into(),
            s(&mesh),
            "--ct".into(),
            s(&ct),
            "--out".into(),
            s(&dir.join("m-out")),
        ],
    ] {
        let o = common::run(
            std::process::Command::new(env!("CARGO_BIN_EXE_atlasmesh")).args(&args),
            common::deadline::ATLASMESH,
        );
        let all =
            String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
        eprintln!("{}: {all}", args[0]);
        assert!(!all.is_empty(), "{args:?}: no output");
        for line in all.lines() {
            assert!(
                !line.starts_with("error: forged") && !line.starts_with("warning: forged"),
                "{args:?}: a name started a line: {all}"
            );
            assert!(
                !line.contains('\u{1b}'),
                "{args:?}: an escape code reached the terminal: {all:?}"
            );
        }
    }
}

/// A 6³ block of label 1 inside an 8³ image.
fn block() -> Vec<u8> {
    let mut v = vec![0u8; 512];
    for z in 1..7 {
        for y in 1..7 {
            for x in 1..7 {
                v[x + 8 * (y + 8 * z)] = 1;
            }
        }
    }
    v
}

#[test]
fn bad_label_maps_are_refused_with_the_file_and_the_problem() {
    let dir = common::temp_dir("bad-label-maps");
    let gz = gzip;
    let good = nifti1([8, 8, 8], 2, 8, [1.0, 1.0, 2.0], true, &block());
    let mut floats = Vec::new();
    for (k, v) in block().iter().enumerate() {
        let f = if k == 100 { f32::NAN } else { f32::from(*v) };
        floats.extend_from_slice(&f.to_le_bytes());
    }
    let mut cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("truncated.nii.gz", gz(&good)[..60].to_vec(), "cut short"),
        ("short.nii", good[..600].to_vec(), "truncated"),
        (
            "huge.nii.gz",
            gz(&nifti1(
                [30000, 30000, 30000],
                2,
                8,
                [1.0; 3],
                true,
                &block(),
            )),
            "input limit",
        ),
        (
            "complex.nii",
            nifti1([8, 8, 8], 32, 64, [1.0; 3], true, &[0u8; 4096]),
            "datatype 32",
        ),
        (
            "nan.nii",
            nifti1([8, 8, 8], 16, 32, [1.0; 3], true, &floats),
            "NaN",
        ),
        (
            "flat.nii",
            nifti1([8, 8, 8], 2, 8, [1.0, 0.0, 1.0], false, &block()),
            "degenerate",
        ),
        (
            "empty.nii",
            nifti1([8, 8, 8], 2, 8, [1.0; 3], true, &[0u8; 512]),
            "all 0",
        ),
        ("not.nii", b"hello, not an image".to_vec(), "not a NIfTI"),
    ];
    cases.push((
        "bzip.nrrd",
        b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 8 8 8\nencoding: bzip2\n\n".to_vec(),
        "encoding \"bzip2\"",
    ));
    cases.push((
        "away.mhd",
        b"ObjectType = Image\nNDims = 3\nDimSize = 8 8 8\nElementType = MET_UCHAR\nElementDataFile = ../../etc/passwd\n".to_vec(),
        "inside it",
    ));
    // The good one reads (the cases fail for their own reason).
    std::fs::write(dir.join("good.nii.gz"), gz(&good)).unwrap();
    let s = read_label_surface(&dir.join("good.nii.gz"), &label("1")).unwrap();
    let (lo, hi) = atlasmesh::geometry::bounding_box(&s.shape.points);
    // The block spans voxel centres 1..6: its boundary half a voxel beyond (x, y 1 mm; z 2 mm).
    for (k, (want_lo, want_hi)) in [(0.5, 6.5), (0.5, 6.5), (1.0, 13.0)].iter().enumerate() {
        assert!(
            (lo[k] - want_lo).abs() <= 0.5 && (hi[k] - want_hi).abs() <= 0.5,
            "{k}: {lo:?} {hi:?}"
        );
    }
    for (name, bytes, want) in &cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let e = read_label_surface(&path, &label("1"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(name), "{name}: {e}");
        assert!(e.contains(want), "{name}: {e}");
        // The command line: a non-zero exit, the message, nothing written.
        let out = dir.join(format!("{name}.ply"));
        let o = common::atlasmesh(&[
            "convert".into(),
            path.display().to_string(),
            out.display().to_string(),
            "--label".into(),
            "1".into(),
        ]);
        assert!(!o.status.success(), "{name}");
        assert!(String::from_utf8_lossy(&o.stderr).contains(name), "{name}");
        assert!(!out.exists(), "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The index of world point `p` (RAS) in `image`, rounded.
fn voxel_of(image: &atlasmesh::image::Image, p: Point<3>) -> [i64; 3] {
    let a = &image.affine;
    let m = [
        [a[0][0], a[0][1], a[0][2]],
        [a[1][0], a[1][1], a[1][2]],
        [a[2][0], a[2][1], a[2][2]],
    ];
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let q = [p[0] - a[0][3], p[1] - a[1][3], p[2] - a[2][3]];
    // Cramer's rule.
    let solve = |c: usize| {
        let mut mm = m;
        for r in 0..3 {
            mm[r][c] = q[r];
        }
        (mm[0][0] * (mm[1][1] * mm[2][2] - mm[1][2] * mm[2][1])
            - mm[0][1] * (mm[1][0] * mm[2][2] - mm[1][2] * mm[2][0])
            + mm[0][2] * (mm[1][0] * mm[2][1] - mm[1][1] * mm[2][0]))
            / det
    };
    std::array::from_fn(|c| solve(c).round() as i64)
}

#[test]
fn totalsegmentators_l1_is_fitted_with_an_atlas_of_verse_vertebrae_in_the_cts_frame() {
    let Some(data) = common::data_dir("TotalSegmentator L1") else {
        return;
    };
    let dir = common::temp_dir("totalseg-l1");
    let raw = data.join("verse-L1-vertebrae-3d/raw");
    let mut shapes: Vec<String> = std::fs::read_dir(&raw)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .map(|p| p.display().to_string())
        .collect();
    shapes.sort();
    let atlas = dir.join("atlas.safetensors");
    let mut args = vec!["build".to_string(), "--register".into(), "--shapes".into()];
    args.extend(shapes);
    args.extend(["--out".into(), atlas.display().to_string()]);
    let o = common::atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ts = data.join("totalseg-example-ct-3d");
    let seg = ts.join("example_seg.nii.gz");
    let out = dir.join("fit");
    let o = common::atlasmesh(&[
        "fit".into(),
        "--atlas".into(),
        atlas.display().to_string(),
        "--subjects".into(),
        seg.display().to_string(),
        "--label".into(),
        "vertebrae_L1".into(),
        "--label-table".into(),
        ts.join("labels_total.csv").display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ]);
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stderr),
        String::from_utf8_lossy(&o.stdout)
    );
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let s = &r.subjects[0];
    eprintln!(
        "TotalSegmentator L1: mesh RMS {:.3} mm p95 {:.3} max {:.3}; success {}; {:?}",
        s.mesh_rms_distance, s.mesh_p95_distance, s.mesh_max_distance, s.success, s.warnings
    );
    assert!(s.mesh_rms_distance <= 1.5, "{}", s.mesh_rms_distance);
    // Distances in voxels too: the report and the page.
    assert!(
        (s.voxel_size.unwrap() - 3.0).abs() < 1e-3,
        "{:?}",
        s.voxel_size
    );
    let page = std::fs::read_to_string(out.join(&s.name).join(format!("{}.html", s.name))).unwrap();
    assert!(page.contains("mesh RMS distance in voxels"));
    assert!(s.success, "{:?}", s.failed_checks);
    // The delivered mesh lies on the label in the CT's frame: every node inside label 31 or
    // within one voxel of it.
    let vtu = out.join(&s.name).join(format!("{}_mesh.vtu", s.name));
    let mesh: atlasmesh::mesh::FeMesh<3> = atlasmesh::formats::read_fe_mesh(&vtu).unwrap();
    // The nodes as meshio reads the file (atlasmesh's own reader without a Python).
    let nodes: Vec<Point<3>> = match common::meshio_meshes(std::slice::from_ref(&vtu)) {
        Some(read) => read[0].0.iter().map(|p| [p[0], p[1], p[2]]).collect(),
        None => mesh.nodes.clone(),
    };
    assert_eq!(nodes.len(), mesh.nodes.len());
    let image = atlasmesh::formats::read_image(&seg).unwrap().image;
    let [nx, ny, nz] = image.dims.map(|d| d as i64);
    let is31 = |i: i64, j: i64, k: i64| {
        (0..nx).contains(&i)
            && (0..ny).contains(&j)
            && (0..nz).contains(&k)
            && image.value((i + nx * (j + ny * k)) as usize) == 31.0
    };
    let far = nodes
        .iter()
        .filter(|p| {
            let [i, j, k] = voxel_of(&image, **p);
            !(-1..=1).any(|a| (-1..=1).any(|b| (-1..=1).any(|c| is31(i + a, j + b, k + c))))
        })
        .count();
    assert_eq!(
        far,
        0,
        "{far} of {} nodes more than a voxel from label 31",
        nodes.len()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The world positions (RAS) of every voxel centre of `image` that `keep` selects.
fn centres(
    image: &atlasmesh::image::Image,
    keep: impl Fn([usize; 3]) -> bool,
) -> Vec<(Point<3>, [usize; 3])> {
    let [nx, ny, nz] = image.dims;
    let mut v = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                if keep([i, j, k]) {
                    v.push((image.world([i as f64, j as f64, k as f64]), [i, j, k]));
                }
            }
        }
    }
    v
}

#[test]
fn a_dicom_series_is_read_to_the_geometry_totalsegmentator_gave_it() {
    let Some(data) = common::data_dir("DICOM series") else {
        return;
    };
    let ts = data.join("totalseg-example-ct-3d");
    let ct = atlasmesh::formats::read_image(&ts.join("example_ct_dicom"))
        .unwrap()
        .image;
    let seg = atlasmesh::formats::read_image(&ts.join("example_seg_dicom.nii.gz"))
        .unwrap()
        .image;
    assert_eq!(ct.voxel_count(), seg.voxel_count());
    assert_eq!(ct.file_convention, atlasmesh::image::WorldConvention::Lps);
    // Every voxel centre of the label map (dcm2niix's RAS grid, its own axis order) is a voxel
    // centre of the series within 0.01 mm.
    let every_7th = |[i, j, k]: [usize; 3]| (i + j + k) % 7 == 0 || i == 0 || j == 0 || k == 0;
    let mut worst: f64 = 0.0;
    for (p, ijk) in centres(&seg, every_7th) {
        let [a, b, c] = voxel_of(&ct, p);
        assert!(
            (0..ct.dims[0] as i64).contains(&a)
                && (0..ct.dims[1] as i64).contains(&b)
                && (0..ct.dims[2] as i64).contains(&c),
            "label voxel {ijk:?} at {p:?} falls outside the series"
        );
        let q = ct.world([a as f64, b as f64, c as f64]);
        worst = worst.max(atlasmesh::geometry::dist2(p, q).sqrt());
    }
    eprintln!("DICOM series vs dcm2niix: worst voxel centre {worst:.2e} mm");
    assert!(worst <= 0.01, "{worst} mm");
    // Hounsfield units, the rescale applied: slice by slice as pydicom (with OpenJPEG)
    // decodes the JPEG 2000 files (the slices sorted along z, LPS's superior).
    let slices: Vec<(f64, f64, f64, f64)> = (0..ct.dims[2])
        .map(|k| {
            let n = ct.dims[0] * ct.dims[1];
            let v: Vec<f64> = (k * n..(k + 1) * n).map(|i| ct.value(i)).collect();
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            (
                ct.world([0.0, 0.0, k as f64])[2],
                lo,
                hi,
                v.iter().sum::<f64>(),
            )
        })
        .collect();
    assert_eq!(
        slices.iter().map(|s| s.1).fold(f64::INFINITY, f64::min),
        -1024.0
    );
    let Some(py) = common::python() else {
        return;
    };
    let script = r#"
import sys, glob, json, pydicom
out = []
for f in glob.glob(sys.argv[1] + "/*"):
    d = pydicom.dcmread(f)
    a = d.pixel_array.astype(float) * float(d.RescaleSlope) + float(d.RescaleIntercept)
    out.append([float(d.ImagePositionPatient[2]), a.min(), a.max(), a.sum()])
print(json.dumps(sorted(out)))
"#;
    let o = crate::common::run(
        std::process::Command::new(py)
            .arg("-c")
            .arg(script)
            .arg(ts.join("example_ct_dicom")),
        crate::common::deadline::PYTHON,
    );
    assert!(
        o.status.success(),
        "pydicom: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let theirs: Vec<(f64, f64, f64, f64)> = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(theirs.len(), slices.len());
    for (a, b) in slices.iter().zip(&theirs) {
        assert!((a.0 - b.0).abs() < 1e-6, "slice order: {a:?} {b:?}");
        assert_eq!((a.1, a.2, a.3), (b.1, b.2, b.3), "slice at z {}", a.0);
    }
}

#[test]
fn a_dicom_folder_with_a_missing_slice_or_two_series_is_refused() {
    let Some(data) = common::data_dir("bad DICOM series") else {
        return;
    };
    let series = data.join("totalseg-example-ct-3d/example_ct_dicom");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&series)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    let dir = common::temp_dir("bad-dicom");
    let gap = dir.join("gap");
    std::fs::create_dir_all(&gap).unwrap();
    for (k, f) in files.iter().enumerate() {
        if k != 7 {
            std::fs::copy(f, gap.join(f.file_name().unwrap())).unwrap();
        }
    }
    let e = atlasmesh::formats::read_image(&gap)
        .unwrap_err()
        .to_string();
    assert!(e.contains("gap") && e.contains("missing slices"), "{e}");
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    std::fs::write(empty.join("notes.txt"), "no images here").unwrap();
    let e = atlasmesh::formats::read_image(&empty)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no DICOM file"), "{e}");
    // A second series in the folder (one slice re-labelled by pydicom).
    let Some(py) = common::python() else {
        return;
    };
    let mixed = dir.join("mixed");
    std::fs::create_dir_all(&mixed).unwrap();
    for f in &files {
        std::fs::copy(f, mixed.join(f.file_name().unwrap())).unwrap();
    }
    let one = mixed.join(files[3].file_name().unwrap());
    let script = "import sys, pydicom; d = pydicom.dcmread(sys.argv[1]); d.SeriesInstanceUID = '1.2.826.0.1.3680043.8.498.1'; d.save_as(sys.argv[1])";
    let o = crate::common::run(
        std::process::Command::new(py)
            .arg("-c")
            .arg(script)
            .arg(&one),
        crate::common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let e = atlasmesh::formats::read_image(&mixed)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("2 series mixed") && e.contains("1.2.826.0.1.3680043.8.498.1"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_same_label_map_as_other_writers_save_it_gives_the_same_surface() {
    let Some(data) = common::data_dir("label map writers") else {
        return;
    };
    let Some(py) = common::python() else {
        return;
    };
    let src = data.join("verse-L1-labelmaps-3d/sub-verse018_segment_20.nii.gz");
    let dir = common::temp_dir("label-writers");
    // SimpleITK (ITK's writers: LPS) and nibabel (RAS): detached NRRD with raw data, attached
    // raw NRRD, uncompressed MetaImage, NIfTI-2, big-endian NIfTI-1.
    let script = r#"
import sys, os, SimpleITK as sitk, nibabel as nib, numpy as np
src, out = sys.argv[1], sys.argv[2]
img = sitk.ReadImage(src)
sitk.WriteImage(img, os.path.join(out, "m.nhdr"), useCompression=False)
sitk.WriteImage(img, os.path.join(out, "m.nrrd"), useCompression=False)
sitk.WriteImage(img, os.path.join(out, "m.mha"), useCompression=False)
n = nib.load(src)
nib.save(nib.Nifti2Image(np.asanyarray(n.dataobj), n.affine, dtype=np.int16), os.path.join(out, "m2.nii"))
h = n.header.copy()
h = h.as_byteswapped(">")
nib.save(nib.Nifti1Image(np.asanyarray(n.dataobj).astype(">i2"), n.affine, h), os.path.join(out, "mbe.nii"))
"#;
    let o = crate::common::run(
        std::process::Command::new(py)
            .arg("-c")
            .arg(script)
            .arg(&src)
            .arg(&dir),
        crate::common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let reference = read_label_surface(&src, &label("20")).unwrap();
    for name in ["m.nhdr", "m.nrrd", "m.mha", "m2.nii", "mbe.nii"] {
        let s = read_label_surface(&dir.join(name), &label("20")).unwrap();
        assert_eq!(s.shape.facets, reference.shape.facets, "{name}");
        let worst = s
            .shape
            .points
            .iter()
            .zip(&reference.shape.points)
            .map(|(a, b)| atlasmesh::geometry::dist2(*a, *b).sqrt())
            .fold(0.0, f64::max);
        assert!(worst < 1e-4, "{name}: {worst} mm from the NIfTI's surface");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
