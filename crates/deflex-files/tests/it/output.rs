//! The output discipline ([`deflex_files::atomic`], [`deflex_files::output`]) against what a
//! careful user and a killed or concurrent run do.

use crate::scratch;
use deflex_files::*;
use std::fs;
use std::io::Write;
use std::path::Path;

fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
}

/// A process id no process has (above every Linux pid_max).
const DEAD_PID: u32 = 2_147_483_646;

#[test]
fn a_file_appears_only_on_commit_and_an_abandoned_one_keeps_the_old() {
    let dir = scratch("file");
    let path = dir.join("log.csv");
    fs::write(&path, "old").unwrap();
    {
        let mut file = AtomicFile::create(&path).unwrap();
        file.write_all(b"half").unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "old");
        // dropped without commit: a failed run
    }
    assert_eq!(fs::read_to_string(&path).unwrap(), "old");
    assert_eq!(entries(&dir), vec!["log.csv"], "no temporary left behind");
    write_atomic(&path, "new").unwrap();
    assert_eq!(fs::read_to_string(&path).unwrap(), "new");
    assert_eq!(entries(&dir), vec!["log.csv"]);
    fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_folder_is_swapped_in_whole_and_an_abandoned_one_keeps_the_old() {
    let dir = scratch("dir");
    let out = dir.join("report");
    let first = AtomicDir::create(&out).unwrap();
    fs::write(first.path().join("a.csv"), "old").unwrap();
    first.commit().unwrap();
    {
        let building = AtomicDir::create(&out).unwrap();
        fs::write(building.path().join("a.csv"), "half").unwrap();
        // dropped: a failed validation
    }
    assert_eq!(fs::read_to_string(out.join("a.csv")).unwrap(), "old");
    assert_eq!(entries(&dir), vec![".report.lock", "report"]);
    let building = AtomicDir::create(&out).unwrap();
    fs::write(building.path().join("b.csv"), "new").unwrap();
    building.commit().unwrap();
    assert_eq!(entries(&out), vec![MARKER, "b.csv"]);
    assert_eq!(entries(&dir), vec![".report.lock", "report"]);
    fs::remove_dir_all(dir).unwrap();
}

#[test]
fn write_through_keeps_the_extension_and_cleans_up_on_failure() {
    let dir = scratch("through");
    let path = dir.join("plot.png");
    fs::write(&path, "old").unwrap();
    let failed: std::io::Result<()> = write_through(
        &path,
        |tmp| {
            assert_eq!(tmp.extension().unwrap(), "png");
            fs::write(tmp, "half").unwrap();
            Err(std::io::Error::other("drawing failed"))
        },
        |e| e,
    );
    assert!(failed.is_err());
    assert_eq!(fs::read_to_string(&path).unwrap(), "old");
    assert_eq!(entries(&dir), vec!["plot.png"]);
    write_through(&path, |tmp| fs::write(tmp, "new"), |e| e).unwrap();
    assert_eq!(fs::read_to_string(&path).unwrap(), "new");
    assert_eq!(entries(&dir), vec!["plot.png"]);
    fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_path_without_a_file_name_is_an_error() {
    assert!(write_atomic("/", "x").is_err());
}

#[test]
fn devices_fifos_and_links_to_them_are_never_replaced() {
    let dir = scratch("special");
    let fifo = dir.join("pipe");
    mkfifo(&fifo);
    let to_null = dir.join("to-null");
    std::os::unix::fs::symlink("/dev/null", &to_null).unwrap();
    let dangling = dir.join("dangling");
    std::os::unix::fs::symlink(dir.join("nowhere"), &dangling).unwrap();
    for path in [Path::new("/dev/null"), &fifo, &to_null] {
        let e = write_atomic(path, "x").unwrap_err();
        assert!(
            matches!(problem_of(&e), Some(OutputProblem::NotAFile { .. })),
            "{}: {e}",
            path.display()
        );
        let e = AtomicFile::create(path).err().unwrap();
        assert!(problem_of(&e).is_some(), "{e}");
        let e = write_through(path, |t| fs::write(t, "x"), |e| e).unwrap_err();
        assert!(problem_of(&e).is_some(), "{e}");
        let e = AtomicDir::create(path).err().unwrap();
        assert!(
            matches!(problem_of(&e), Some(OutputProblem::NotAFolder { .. })),
            "{e}"
        );
    }
    let e = write_atomic(&dangling, "x").unwrap_err();
    assert!(
        matches!(problem_of(&e), Some(OutputProblem::DanglingLink { .. })),
        "{e}"
    );
    // a folder given as a file output
    let e = write_atomic(&dir, "x").unwrap_err();
    assert!(matches!(
        problem_of(&e),
        Some(OutputProblem::NotAFile {
            kind: FileKind::Folder
        })
    ));
    let e = check_output_flag("--out", Path::new("/dev/null"), OutputKind::File).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("--out /dev/null: is a character device"),
        "{e}"
    );
    let mut found = entries(&dir);
    found.sort();
    assert_eq!(
        found,
        vec!["dangling", "pipe", "to-null"],
        "nothing created or replaced"
    );
    assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    fs::remove_dir_all(dir).unwrap();
}

use std::os::unix::fs::FileTypeExt;

#[test]
fn a_link_to_a_file_is_written_through_and_kept() {
    let dir = scratch("link");
    let target = dir.join("model.toml");
    fs::write(&target, "old").unwrap();
    let link = dir.join("current.toml");
    std::os::unix::fs::symlink("model.toml", &link).unwrap();
    write_atomic(&link, "new").unwrap();
    assert!(
        fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(fs::read_to_string(&target).unwrap(), "new");
    fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_foreign_folder_is_refused_and_an_empty_or_own_one_replaced() {
    let dir = scratch("foreign");
    let home = dir.join("home");
    fs::create_dir(&home).unwrap();
    fs::write(home.join("thesis.tex"), "years of work").unwrap();
    let e = AtomicDir::create(&home).err().unwrap();
    assert!(
        matches!(problem_of(&e), Some(OutputProblem::ForeignFolder)),
        "{e}"
    );
    assert_eq!(
        fs::read_to_string(home.join("thesis.tex")).unwrap(),
        "years of work"
    );
    let empty = dir.join("empty");
    fs::create_dir(&empty).unwrap();
    let building = AtomicDir::create(&empty).unwrap();
    fs::write(building.path().join("a"), "1").unwrap();
    building.commit().unwrap();
    AtomicDir::create(&empty).unwrap().commit().unwrap();
    assert_eq!(entries(&empty), vec![MARKER]);
    fs::remove_dir_all(dir).unwrap();
}

#[test]
fn an_output_that_is_an_input_is_refused() {
    track_inputs();
    let dir = scratch("input");
    let data = dir.join("readings.csv");
    fs::write(&data, "a,b\n1,2\n").unwrap();
    read_bounded(&data, 1000).unwrap();
    let e = write_atomic(&data, "predicted").unwrap_err();
    assert!(
        matches!(problem_of(&e), Some(OutputProblem::IsAnInput { .. })),
        "{e}"
    );
    // by identity, not by name: a hard link to it is the same file
    let alias = dir.join("alias.csv");
    fs::hard_link(&data, &alias).unwrap();
    assert!(write_atomic(&alias, "x").is_err());
    assert_eq!(fs::read_to_string(&data).unwrap(), "a,b\n1,2\n");
    // a folder output holding an input
    let e = AtomicDir::create(&dir).err().unwrap();
    assert!(
        matches!(
            problem_of(&e),
            Some(OutputProblem::HoldsAnInput { .. }) | Some(OutputProblem::ForeignFolder)
        ),
        "{e}"
    );
    fs::remove_dir_all(dir).unwrap();
}

#[test]
fn leftovers_of_killed_runs_are_cleaned_and_only_theirs() {
    let dir = scratch("leftovers");
    let path = dir.join("log.csv");
    let dead = dir.join(format!(".log.csv.tmp-{DEAD_PID}-3"));
    let alive = dir.join(format!(".log.csv.tmp-{}-999999", std::process::id()));
    let other = dir.join(format!(".log.csv.tmp-{DEAD_PID}-x"));
    for p in [&dead, &alive, &other] {
        fs::write(p, "half").unwrap();
    }
    write_atomic(&path, "new").unwrap();
    assert!(!dead.exists(), "a dead process's temporary is removed");
    assert!(alive.exists(), "a running process's temporary is kept");
    assert!(other.exists(), "a name not of the exact pattern is kept");
    // a folder: every temporary of the output is stale once the lock is held
    let out = dir.join("demo");
    let killed = dir.join(format!(".demo.tmp-{}-7", std::process::id()));
    fs::create_dir(&killed).unwrap();
    fs::write(killed.join("index.html"), "half").unwrap();
    AtomicDir::create(&out).unwrap().commit().unwrap();
    assert!(!killed.exists());
    fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_swap_killed_between_its_renames_is_repaired_by_the_next_run() {
    let dir = scratch("swap");
    let out = dir.join("programs");
    // the state a kill leaves after "old aside" and before "new in"
    let aside = dir.join(format!(".programs.old-{DEAD_PID}-0"));
    fs::create_dir(&aside).unwrap();
    fs::write(aside.join(MARKER), "").unwrap();
    fs::write(aside.join("prog.src"), "old").unwrap();
    {
        let failing = AtomicDir::create(&out).unwrap();
        assert_eq!(fs::read_to_string(out.join("prog.src")).unwrap(), "old");
        drop(failing);
    }
    assert_eq!(fs::read_to_string(out.join("prog.src")).unwrap(), "old");
    assert!(!aside.exists());
    fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_second_run_on_a_folder_is_refused_with_the_first_ones_pid() {
    let dir = scratch("lock");
    let out = dir.join("map");
    let first = AtomicDir::create(&out).unwrap();
    let e = AtomicDir::create(&out).err().unwrap();
    match problem_of(&e) {
        Some(OutputProblem::InUse { holder }) => {
            assert!(holder.contains(&std::process::id().to_string()), "{holder}")
        }
        other => panic!("{other:?}"),
    }
    first.commit().unwrap();
    AtomicDir::create(&out).unwrap().commit().unwrap();
    fs::remove_dir_all(dir).unwrap();
}
