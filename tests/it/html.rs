//! `report.html` in a real browser (issue 9): the demo's 2D and 3D reports opened in headless
//! Chromium (Debian `chromium`, installed by `.ci/run`): every image decodes, no script error,
//! every link names a file that exists, and a screenshot is taken.

use crate::common;

use std::process::Command;

fn chromium(args: &[&str], page: &std::path::Path) -> std::process::Output {
    Command::new("chromium")
        .args([
            "--headless=new",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--virtual-time-budget=10000",
        ])
        .args(args)
        .arg(format!("file://{}", page.display()))
        .output()
        .unwrap()
}

fn attribute(body: &str, name: &str) -> Option<String> {
    let at = body.find(&format!("{name}=\""))? + name.len() + 2;
    let end = body[at..].find('"')?;
    Some(body[at..at + end].to_string())
}

#[test]
fn the_demo_report_opens_in_chromium_with_every_image() {
    if !common::tool("chromium", "report.html in headless Chromium") {
        return;
    }
    let d = common::temp_dir("html");
    let out = d.join("demo");
    let o = Command::new(env!("CARGO_BIN_EXE_atlasmesh"))
        .args(["demo", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.trim_end().ends_with("report.html"),
        "the demo ends with the path of its report.html: {stdout}"
    );
    for (page, least) in [
        (out.join("report.html"), 10),
        (out.join("3d/report.html"), 10),
    ] {
        assert!(page.is_file(), "{}", page.display());
        let o = chromium(&["--enable-logging=stderr", "--v=0", "--dump-dom"], &page);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let dom = String::from_utf8_lossy(&o.stdout);
        let body = dom
            .split("<body")
            .nth(1)
            .and_then(|b| b.split('>').next())
            .unwrap_or_default()
            .to_string();
        let images: usize = attribute(&body, "data-images")
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("the page's check did not run: <body{body}>"));
        assert!(images >= least, "{images} images in {}", page.display());
        assert_eq!(
            attribute(&body, "data-broken").as_deref(),
            Some("0"),
            "broken images in {}",
            page.display()
        );
        assert_eq!(
            attribute(&body, "data-errors").as_deref(),
            Some(""),
            "script errors in {}",
            page.display()
        );
        // Every subject's files are linked, and every link names a file beside the page.
        let links: Vec<&str> = dom
            .split("href=\"")
            .skip(1)
            .filter_map(|r| r.split('"').next())
            .collect();
        assert!(
            links.len() >= 10,
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
            "console errors: {log}"
        );
        let shot = d.join("shot.png");
        let _ = std::fs::remove_file(&shot);
        let o = chromium(
            &[
                "--window-size=1400,1800",
                &format!("--screenshot={}", shot.display()),
            ],
            &page,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let png = std::fs::read(&shot).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        assert!(png.len() > 50_000, "screenshot of {} bytes", png.len());
    }
    std::fs::remove_dir_all(&d).ok();
}
