//! The output folder of `deflex compensate`, written whole or not at all: the table, the
//! programs (each read back) and the summaries.

use super::summary::run_json;
use super::{CompensationRun, ProgramPlan, description, refusal, summary_text, table_comments};
use crate::error::{Error, Result};
use deflex_compensate::table::write_csv_to;
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

/// What a run reports once its folder is written.
pub struct FolderSummary {
    /// `summary.json`.
    pub json: Value,
    /// `summary.txt`, the text the CLI prints.
    pub text: String,
    /// Why the run is refused (points not compensated, no convergence): the table and the
    /// summaries are written (where no earlier folder exists), no program is.
    pub refusal: Option<Error>,
}

/// Write the output folder `out` of a run whole: `compensated_path.csv`, `summary.json`,
/// `summary.txt` and, when the run is not refused, `programs/` with one program per format,
/// each read back. A refused run replaces no earlier folder: its table and summaries are
/// written only where `out` does not exist yet. The compensation is freed once the programs'
/// input is made.
pub fn write_output_folder(run: CompensationRun, out: &Path) -> Result<FolderSummary> {
    let dir = deflex_files::AtomicDir::create(out).map_err(Error::io_on(out))?;
    let mut written = Vec::new();
    let table_path = dir.path().join("compensated_path.csv");
    let mut table =
        deflex_files::AtomicFile::create(&table_path).map_err(Error::io_on(&table_path))?;
    write_csv_to(
        &mut table,
        &run.setup.path,
        &run.result,
        run.setup.robot.joint_count(),
        &table_comments(&run),
    )
    .and_then(|()| table.flush())
    .map_err(Error::io_on(&table_path))?;
    table.commit().map_err(Error::io_on(&table_path))?;
    written.push("compensated_path.csv".to_string());
    let refusal = refusal(&run).err();
    let mut text = summary_text(&run);
    let mut summary = run_json(&run);
    let mut program_json = Vec::new();
    let program_description = description(&run);
    let CompensationRun { setup, result, .. } = run;
    if refusal.is_none() && !setup.formats.is_empty() {
        let programs_dir = dir.path().join("programs");
        std::fs::create_dir_all(&programs_dir).map_err(Error::io_on(&programs_dir))?;
        let plan = ProgramPlan::new(&setup, &result, program_description, &setup.settings)?;
        // The programs need the plan only; the rest of the result is in the table and the
        // summaries: free it.
        drop(result);
        for format in &setup.formats {
            let check = plan.write_checked(*format, &setup.settings, &programs_dir)?;
            written.extend(check.files.iter().map(|f| format!("programs/{f}")));
            let _ = writeln!(text, "  {}", check.line());
            program_json.push(check.json());
        }
    } else {
        drop(result);
    }
    written.push("summary.json".into());
    written.push("summary.txt".into());
    summary.insert("programs".into(), json!(program_json));
    summary.insert("out".into(), json!(out.display().to_string()));
    summary.insert("files".into(), json!(written));
    let summary = Value::Object(summary);
    let programs = written
        .iter()
        .filter(|f| f.starts_with("programs/"))
        .count();
    let others: Vec<&str> = written
        .iter()
        .filter(|f| !f.starts_with("programs/"))
        .map(String::as_str)
        .collect();
    // A failed run keeps an earlier result whole (nothing swapped in); where there is none, its
    // table and summaries are written for diagnosis.
    let keep_earlier = refusal.is_some() && std::fs::symlink_metadata(out).is_ok();
    if keep_earlier {
        let _ = writeln!(
            text,
            "  nothing written: {} is kept as it was (a failed run replaces no earlier result)",
            deflex_files::shown_path(out)
        );
    } else {
        let _ = writeln!(
            text,
            "  wrote {}{}; none of the programs has been run on a real controller",
            others.join(", "),
            if programs > 0 {
                format!(" and {programs} program file(s) in programs/")
            } else {
                String::new()
            }
        );
    }
    let json_text = serde_json::to_string_pretty(&summary).map_err(|e| Error::Serialise {
        what: "summary.json",
        reason: e.to_string(),
    })?;
    deflex_files::write_atomic(dir.path().join("summary.json"), json_text)
        .map_err(Error::io_on(out))?;
    deflex_files::write_atomic(dir.path().join("summary.txt"), &text).map_err(Error::io_on(out))?;
    if !keep_earlier {
        dir.commit().map_err(Error::io_on(out))?;
    }
    Ok(FolderSummary {
        json: summary,
        text,
        refusal,
    })
}
