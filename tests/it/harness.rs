//! The tests' own helpers: a program past its deadline is killed with every process it
//! started and reported with its output; a test's folder goes with its guard, pass or fail.

use crate::common;

use std::process::Command;
use std::time::{Duration, Instant};

/// Waits up to 5 s for `pid` to end.
fn ends(pid: u32) -> bool {
    let t = Instant::now();
    while common::alive(pid) {
        if t.elapsed() > Duration::from_secs(5) {
            return false;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    true
}

/// The pid a shell wrote to `file`.
fn pid_in(file: &std::path::Path) -> u32 {
    std::fs::read_to_string(file)
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

#[test]
fn a_program_past_its_deadline_is_killed_with_its_children_and_reported() {
    let d = common::temp_dir("deadline");
    let pid_file = d.join("child.pid");
    let t = Instant::now();
    let e = common::try_run(
        Command::new("sh").arg("-c").arg(format!(
            "sleep 300 & echo $! > '{}'; echo started; echo waiting >&2; wait",
            pid_file.display()
        )),
        Duration::from_secs(1),
    )
    .unwrap_err();
    assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
    assert!(e.contains("killed at its deadline of 1 s"), "{e}");
    assert!(e.contains("started") && e.contains("waiting"), "{e}");
    let child = pid_in(&pid_file);
    assert!(
        ends(child),
        "the program's child {child} outlived the deadline"
    );
    // In time: the status and both outputs, whole.
    let o = common::run(
        Command::new("sh")
            .arg("-c")
            .arg("echo out; echo err >&2; exit 3"),
        Duration::from_secs(30),
    );
    assert_eq!(o.status.code(), Some(3));
    assert_eq!(
        (&o.stdout[..], &o.stderr[..]),
        (&b"out\n"[..], &b"err\n"[..])
    );
    // A program that exits leaving a child behind: the child is ended too.
    let o = common::run(
        Command::new("sh").arg("-c").arg(format!(
            "sleep 300 > /dev/null 2>&1 & echo $! > '{}'",
            pid_file.display()
        )),
        Duration::from_secs(30),
    );
    assert!(o.status.success());
    let child = pid_in(&pid_file);
    assert!(
        ends(child),
        "the child {child} left by a program outlived it"
    );
    // A program that does not exist: an error naming it.
    let e = common::try_run(
        &mut Command::new("atlasmesh-no-such-program"),
        Duration::from_secs(5),
    )
    .unwrap_err();
    assert!(
        e.contains("atlasmesh-no-such-program: could not start"),
        "{e}"
    );
}

#[test]
fn a_tests_folder_goes_with_its_guard_pass_or_fail() {
    if std::env::var_os("ATLASMESH_KEEP_TMP").is_some_and(|v| !v.is_empty() && v != "0") {
        eprintln!("test folders: not checked (ATLASMESH_KEEP_TMP keeps them)");
        return;
    }
    let kept = {
        let d = common::temp_dir("guard");
        std::fs::create_dir_all(d.join("a/b")).unwrap();
        std::fs::write(d.join("a/b/f.txt"), "x").unwrap();
        d.to_path_buf()
    };
    assert!(!kept.exists(), "{} left after its test", kept.display());
    let failed = std::panic::catch_unwind(|| {
        let d = common::temp_dir("guard-failed");
        std::fs::write(d.join("f.txt"), "x").unwrap();
        panic!("{}", d.display());
    })
    .unwrap_err();
    let path = failed.downcast_ref::<String>().unwrap();
    assert!(path.contains("atlasmesh-guard-failed-"), "{path}");
    assert!(
        !std::path::Path::new(path).exists(),
        "{path} left after a failed test"
    );
}
