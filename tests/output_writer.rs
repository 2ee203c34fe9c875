//! The output writer thread of a dynamic run (docs/decisions/0042-output-writer-thread.md):
//! it writes the same bytes as the writing on the run's own thread, and an error while
//! it writes a frame stops the run with that error, naming the file.

mod common;
use dfem::analysis::{self, progress::Silent};
use dfem::output::StreamWriter;
use std::path::Path;
use std::process::Command;

/// [`common::sliding_box`] with a checkpoint every 20 steps and `output` added to
/// `[output]`.
fn scene_text(output: &str) -> String {
    common::sliding_box(&format!("[output]\ncheckpoint_every = 20\n{output}"))
}

/// Run `text` through a [`StreamWriter`] into `dir`, on a writer thread or not; the
/// outcome's history and the writer's end.
fn stream(
    text: &str,
    dir: &Path,
    threaded: bool,
) -> dfem::Result<dfem::analysis::dynamics::History> {
    let sc = common::scene(text);
    let m = dfem::mesh::build(&sc);
    let mut backend = dfem::solve::backend(dfem::solve::DEFAULT).unwrap();
    std::thread::scope(|scope| {
        let w = StreamWriter::new(dir, &sc, &m)?;
        let mut w = if threaded { w.on_thread(scope)? } else { w };
        let run = analysis::run_with(&sc, &m, None, backend.as_mut(), &mut Silent, &mut w);
        // the writer's error first: the one that stopped the run
        let end = w.finish();
        let out = run?;
        end?;
        Ok(out.history.unwrap())
    })
}

/// The names of the files in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    n.sort();
    n
}

#[test]
fn writer_thread_writes_the_same_bytes_as_the_run_thread() {
    // a frame at every step: 168 frames, 336 .vtu, results.pvd rewritten as they double
    // and at the 9 checkpoints
    let text = scene_text("frame_interval = 0.001");
    let inline = common::tmp_dir("writer_inline");
    let threaded = common::tmp_dir("writer_thread");
    let h = stream(&text, &inline, false).unwrap();
    let h2 = stream(&text, &threaded, true).unwrap();
    assert_eq!(h, h2, "the same run");
    assert_eq!(h.rows.len(), 168);
    let files = names(&inline);
    assert_eq!(files, names(&threaded));
    assert_eq!(files.iter().filter(|f| f.ends_with(".vtu")).count(), 336);
    for f in &files {
        // the summary and the checkpoint hold the wall time
        if f == "summary.json" || f == "checkpoint.bin" {
            continue;
        }
        assert!(
            std::fs::read(inline.join(f)).unwrap() == std::fs::read(threaded.join(f)).unwrap(),
            "{f} differs"
        );
    }
    // the streamed history is every row of the outcome's, formatted as a whole
    assert_eq!(
        std::fs::read_to_string(threaded.join("history.csv")).unwrap(),
        dfem::output::history_csv(&h)
    );
    // results.pvd lists the frames up to the last checkpoint (step 160), at least
    let pvd = std::fs::read_to_string(threaded.join("results.pvd")).unwrap();
    assert!(pvd.contains("file=\"blocks_0160.vtu\""), "{pvd}");
}

#[test]
fn an_error_writing_a_frame_stops_the_run_and_names_the_file() {
    // a non-empty directory where the frame of step 7 (t = 21 ms, the first after 20 ms)
    // goes: the rename onto it fails
    let text = scene_text("");
    for threaded in [false, true] {
        let dir = common::tmp_dir(&format!("writer_error_{threaded}"));
        std::fs::create_dir_all(dir.join("blocks_0007.vtu/x")).unwrap();
        let e = stream(&text, &dir, threaded).unwrap_err().to_string();
        assert!(e.contains("blocks_0007.vtu"), "{e}");
        assert!(e.contains("cannot write the result"), "{e}");
    }
    // the command reports it as a bad outcome, not a panic
    let dir = common::tmp_dir("writer_error_cli");
    std::fs::create_dir_all(dir.join("out/blocks_0007.vtu/x")).unwrap();
    let f = dir.join("scene.toml");
    std::fs::write(&f, &text).unwrap();
    let o = Command::new(common::dfem_bin())
        .arg("run")
        .arg(&f)
        .arg("--out")
        .arg(dir.join("out"))
        .args(["--no-plots", "--quiet"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("blocks_0007.vtu"), "{stderr}");
    assert!(stderr.contains("fix: "), "{stderr}");
    // the frames before it are whole
    assert!(dir.join("out/blocks_0000.vtu").exists());
}
