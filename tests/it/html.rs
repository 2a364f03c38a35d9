//! The report in a real browser: headless Chromium (Debian `chromium`, installed by `.ci/run`;
//! WebGL by SwiftShader) opens the demo's 2D and 3D `report.html`, every subject's page and
//! the model's page, as a user would after `atlasmesh demo`: every image decodes, no script
//! error, every link names a file that exists, every 3D view draws (pixels on its canvas, and
//! in a screenshot the mesh's scaled-Jacobian colours), the model page has its mode slider.
//! With the data, the 40-hand leave-one-out (default options, plots on) keeps its index small.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

fn chromium(args: &[&str], page: &Path) -> std::process::Output {
    chromium_url(args, &format!("file://{}", page.display()))
}

/// Headless Chromium on `url` with `args`, in a profile of its own (a temporary folder,
/// removed after; its temporary files there too), killed with its helpers at the deadline.
fn chromium_url(args: &[&str], url: &str) -> std::process::Output {
    let profile = common::temp_dir("chromium-profile");
    crate::common::run(
        Command::new("chromium")
            .env("TMPDIR", &*profile)
            .arg(format!("--user-data-dir={}", profile.display()))
            .args([
                "--headless=new",
                "--no-sandbox",
                "--disable-gpu",
                // WebGL in software, as on a machine without a GPU.
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--hide-scrollbars",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--virtual-time-budget=15000",
            ])
            .args(args)
            .arg(url),
        crate::common::deadline::CHROMIUM,
    )
}

/// The number of triangles the view of `page` draws, seen from the address `hash`.
fn triangles(page: &Path, hash: &str) -> usize {
    let o = chromium_url(
        &["--dump-dom"],
        &format!("file://{}#{hash}", page.display()),
    );
    let dom = String::from_utf8_lossy(&o.stdout);
    let v = tags(&dom, "<div class=\"am-viewer\"");
    assert_eq!(
        v.first()
            .and_then(|v| attribute(v, "data-state"))
            .as_deref(),
        Some("drawn"),
        "{}#{hash}",
        page.display()
    );
    attribute(v[0], "data-triangles").unwrap().parse().unwrap()
}

fn attribute(tag: &str, name: &str) -> Option<String> {
    let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
    let end = tag[at..].find('"')?;
    Some(tag[at..at + end].to_string())
}

/// The opening tags of the DOM's elements of class `class` (or `<body`).
fn tags<'a>(dom: &'a str, start: &str) -> Vec<&'a str> {
    dom.split(start)
        .skip(1)
        .filter_map(|t| t.split('>').next())
        .collect()
}

/// What a page looks like once loaded: its DOM, checked for images, script errors, console
/// errors and links (every one resolving to a file beside it).
pub fn open(page: &Path, least_images: usize, least_links: usize) -> String {
    assert!(page.is_file(), "{}", page.display());
    let o = chromium(&["--enable-logging=stderr", "--v=0", "--dump-dom"], page);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let dom = String::from_utf8_lossy(&o.stdout).to_string();
    let body = tags(&dom, "<body").first().copied().unwrap_or_default();
    let images: usize = attribute(body, "data-images")
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("the page's check did not run: <body{body}>"));
    assert!(
        images >= least_images,
        "{images} images in {}",
        page.display()
    );
    assert_eq!(
        attribute(body, "data-broken").as_deref(),
        Some("0"),
        "broken images in {}",
        page.display()
    );
    assert_eq!(
        attribute(body, "data-errors").as_deref(),
        Some(""),
        "script errors in {}",
        page.display()
    );
    let links: Vec<&str> = dom
        .split("href=\"")
        .skip(1)
        .filter_map(|r| r.split('"').next())
        .collect();
    assert!(
        links.len() >= least_links,
        "{} links in {}",
        links.len(),
        page.display()
    );
    let dir = page.parent().unwrap();
    for l in &links {
        assert!(dir.join(l).is_file(), "link {l} of {}", page.display());
    }
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(
        !log.lines()
            .any(|l| l.contains("CONSOLE") && (l.contains("Uncaught") || l.contains("Error"))),
        "console errors in {}: {log}",
        page.display()
    );
    dom
}

/// Checks the page's 3D view drew: its state, its triangles, the pixels on its canvas.
fn view_drew(dom: &str, page: &Path) {
    let body = tags(dom, "<body").first().copied().unwrap_or_default();
    assert_eq!(
        attribute(body, "data-viewers-ready").as_deref(),
        Some("yes"),
        "the views of {} did not start: <body{body}>",
        page.display()
    );
    let viewers = tags(dom, "<div class=\"am-viewer\"");
    assert_eq!(viewers.len(), 1, "{}", page.display());
    let v = viewers[0];
    assert_eq!(
        attribute(v, "data-state").as_deref(),
        Some("drawn"),
        "{}: <div{v}>",
        page.display()
    );
    let triangles: usize = attribute(v, "data-triangles").unwrap().parse().unwrap();
    assert!(
        triangles >= 100,
        "{triangles} triangles in {}",
        page.display()
    );
    // More than a twentieth of the 760 × 520 canvas is drawn on.
    let drawn: usize = attribute(v, "data-drawn-pixels").unwrap().parse().unwrap();
    assert!(
        drawn > 760 * 520 / 20,
        "{drawn} pixels drawn in {}",
        page.display()
    );
}

/// How far (pixels) the widest table of `page` goes beyond a window `width` pixels wide, as the
/// page measures it once loaded (`data-overflow`).
fn overflow(page: &Path, width: usize) -> usize {
    let o = chromium(
        &[&format!("--window-size={width},1000"), "--dump-dom"],
        page,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let dom = String::from_utf8_lossy(&o.stdout);
    let body = tags(&dom, "<body").first().copied().unwrap_or_default();
    attribute(body, "data-overflow")
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("the page's check did not run: <body{body}>"))
}

/// A screenshot of `page`: its pixels (RGB rows).
fn screenshot(page: &Path, shot: &Path) -> (usize, usize, Vec<u8>) {
    let _ = std::fs::remove_file(shot);
    let o = chromium(
        &[
            "--window-size=1200,900",
            &format!("--screenshot={}", shot.display()),
        ],
        page,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(shot).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let ch = info.color_type.samples();
    let rgb: Vec<u8> = buf[..info.buffer_size()]
        .chunks(ch)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    (info.width as usize, info.height as usize, rgb)
}

/// Pixels coloured as the scaled Jacobian's good end (green, shaded), in the screenshot.
fn greens(rgb: &[u8]) -> usize {
    rgb.chunks(3)
        .filter(|p| p[1] > 90 && i32::from(p[1]) > i32::from(p[0]) + 30 && p[1] > p[2] + 60)
        .count()
}

/// Each element's smallest scaled Jacobian, of nodes and cells as meshio gives them.
fn sj_of<const D: usize>(
    points: &[Vec<f64>],
    cells: &[Vec<usize>],
    kind: atlasmesh::mesh::ElementKind,
) -> Vec<f64> {
    let m = atlasmesh::mesh::FeMesh::<D> {
        nodes: points
            .iter()
            .map(|p| std::array::from_fn(|d| p[d]))
            .collect(),
        kind,
        connectivity: cells.iter().flatten().copied().collect(),
        sets: Default::default(),
    };
    atlasmesh::mesh::mesh_quality(&m)
        .iter()
        .map(|e| e.scaled_jacobian_min)
        .collect()
}

/// The worst elements a subject's page lists are those of its mesh file, read back by meshio:
/// the first is the element of the smallest scaled Jacobian of the mesh as written (number
/// 1-based, value to the page's 3 decimals), at the mean of its corners.
fn worst_elements_match_the_mesh_file(page: &Path, dim: usize) {
    let mesh_file = page.with_extension("").with_file_name(format!(
        "{}_mesh.vtu",
        page.file_stem().unwrap().to_str().unwrap()
    ));
    let Some(meshes) = common::meshio_meshes(std::slice::from_ref(&mesh_file)) else {
        return;
    };
    let (points, cells) = &meshes[0];
    let html = std::fs::read_to_string(page).unwrap();
    let row = html
        .split("<tr data-focus=\"")
        .nth(1)
        .unwrap_or_else(|| panic!("no worst elements in {}", page.display()));
    let position: Vec<f64> = row
        .split('"')
        .next()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let cols: Vec<&str> = row
        .split("<td>")
        .skip(1)
        .map(|c| c.split("</td>").next().unwrap())
        .collect();
    let (id, sj): (usize, f64) = (cols[0].parse().unwrap(), cols[1].parse().unwrap());
    // The scaled Jacobians of the mesh as meshio reads it, by atlasmesh's measure.
    let q = if dim == 3 {
        sj_of::<3>(points, cells, atlasmesh::mesh::ElementKind::Hex8)
    } else {
        sj_of::<2>(points, cells, atlasmesh::mesh::ElementKind::Quad4)
    };
    let (k, worst) = q
        .iter()
        .copied()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    assert!(
        (sj - worst).abs() <= 5e-4,
        "{}: the page's worst {sj}, the file's {worst}",
        page.display()
    );
    // Ties aside, the same element.
    assert!(
        id == k + 1 || (q[id - 1] - worst).abs() < 1e-12,
        "{}: element {id} listed, {} in the file",
        page.display(),
        k + 1
    );
    let corners = &cells[id - 1];
    for d in 0..3 {
        let c = corners.iter().map(|&n| points[n][d]).sum::<f64>() / corners.len() as f64;
        assert!(
            (c - position[d]).abs() < 1e-5,
            "{}: element {id} at {position:?}",
            page.display()
        );
    }
}

fn pages(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    v.sort();
    v
}

#[test]
fn the_demo_report_opens_in_chromium_and_every_view_draws() {
    if !common::tool("chromium", "report.html in headless Chromium") {
        return;
    }
    let d = common::temp_dir("html");
    let out = d.join("demo");
    let o = crate::common::run(
        Command::new(env!("CARGO_BIN_EXE_atlasmesh"))
            .args(["demo", "--quiet", "--out"])
            .arg(&out),
        crate::common::deadline::ATLASMESH,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.trim_end().ends_with("report.html"),
        "the demo ends with the path of its report.html: {stdout}"
    );
    for dir in [out.clone(), out.join("3d")] {
        // The index: population plots and a thumbnail per subject, linked, not embedded.
        let index = dir.join("report.html");
        let dom = open(&index, 10, 10);
        // Its tables fit a 1400-pixel window: nothing to scroll sideways.
        assert_eq!(
            overflow(&index, 1400),
            0,
            "pixels beyond a 1400-pixel window in {}",
            index.display()
        );
        assert!(!dom.contains("data:image/png"), "{}", index.display());
        assert!(dom.contains("href=\"model.html\""), "{}", index.display());
        let subject_pages: Vec<PathBuf> = pages(&dir, "html")
            .into_iter()
            .filter(|p| !p.ends_with("report.html") && !p.ends_with("model.html"))
            .collect();
        assert_eq!(subject_pages.len(), 6, "{}", dir.display());
        for p in &subject_pages {
            let name = p.file_name().unwrap().to_str().unwrap();
            assert!(dom.contains(&format!("href=\"{name}\"")), "{name} linked");
            // Its files shown by what follows its name (the table fits the window), named
            // whole in their titles.
            let stem = name.trim_end_matches(".html");
            assert!(
                dom.contains(&format!("title=\"{stem}_mesh.vtu\">mesh.vtu</a>"))
                    && dom.contains(&format!("title=\"{name}\">page</a>")),
                "{name}'s files in the index"
            );
            let page = open(p, 1, 3);
            view_drew(&page, p);
            assert!(page.contains("scaled Jacobian"), "{}", p.display());
            worst_elements_match_the_mesh_file(p, if dir == out { 2 } else { 3 });
        }
        let model = dir.join("model.html");
        let page = open(&model, 1, 1);
        view_drew(&page, &model);
        assert!(
            page.contains("class=\"am-w\"") && page.contains("mode 1"),
            "the model page has its mode slider"
        );
        // The modes' variances in both frames, the scale between them said.
        assert!(
            page.contains("variance (the data's unit²)") && page.contains("λ s² with s = "),
            "the model page's variances in the data's unit"
        );
        // Clipped through the middle, the view draws half the boundary and the faces of the
        // cut (3D), half the cells (2D): something, and less than the whole.
        let whole = triangles(&subject_pages[0], "");
        let clipped = triangles(&subject_pages[0], "clip=0,0.5");
        assert!(
            clipped > 0 && clipped < whole,
            "{clipped} triangles clipped, {whole} whole, in {}",
            subject_pages[0].display()
        );
        // An address naming no field of the page (an object's built-in property) is ignored.
        for hash in [
            "color=constructor",
            "color=__proto__",
            "color=toString&clip=1,0.5",
        ] {
            assert!(triangles(&subject_pages[0], hash) > 0, "#{hash}");
        }
        // Seen as a user sees it: the view of the mesh, coloured by scaled Jacobian.
        let (w, h, rgb) = screenshot(&subject_pages[0], &d.join("shot.png"));
        let g = greens(&rgb);
        assert!(
            g > w * h / 50,
            "{g} green pixels of {w} × {h} in the screenshot of {}",
            subject_pages[0].display()
        );
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn the_forty_hands_leave_one_out_index_stays_small() {
    let Some(data) = common::data_dir("the_forty_hands_leave_one_out_index_stays_small") else {
        return;
    };
    let d = common::temp_dir("html-hands");
    let out = d.join("loo");
    let o = crate::common::run(
        Command::new(env!("CARGO_BIN_EXE_atlasmesh"))
            .args(["loo", "--quiet", "--shapes"])
            .arg(data.join("imm-hands-2d/hands_long.csv"))
            .arg("--out")
            .arg(&out),
        crate::common::deadline::ATLASMESH,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    // What the index loads: itself and its pictures.
    let mut bytes = html.len();
    for src in html.split("src=\"").skip(1) {
        let f = src.split('"').next().unwrap();
        bytes += std::fs::metadata(out.join(f)).unwrap().len() as usize;
    }
    assert!(
        bytes < 5 << 20,
        "the index and its pictures weigh {bytes} bytes"
    );
    let pages = pages(&out, "html");
    assert_eq!(pages.len(), 42, "40 subjects, the model and the index");
    if common::tool("chromium", "the hands' report in headless Chromium") {
        open(&out.join("report.html"), 40, 40);
        let page = out.join("0.html");
        let dom = open(&page, 1, 3);
        view_drew(&dom, &page);
    }
    std::fs::remove_dir_all(&d).ok();
}
