//! The output folder of a run that writes frames (`irad render`, `irad reference`). irad
//! records every file it writes there in `.irad-manifest.json`; the next run into the folder
//! removes exactly those, so that two runs' frames never mix, and never a file irad did not
//! write: a file of irad's output shapes (see [`is_run_output`]) that no manifest lists
//! stops the run, unless `overwrite` is set.

use super::{frame_stem, is_run_output, prepare_out_dir};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The manifest's file name in an output folder.
pub const MANIFEST: &str = ".irad-manifest.json";

#[derive(Serialize, Deserialize, Default)]
struct Manifest {
    /// What the file is, for a person who finds it.
    about: String,
    /// The files (names in the folder) irad wrote there, or was about to.
    files: BTreeSet<String>,
}

/// An output folder prepared for a run: what the run may write there is in its manifest.
pub struct RunDir {
    dir: PathBuf,
    planned: BTreeSet<String>,
}

/// The files a run of `frames` writes: each frame's EXR and PNG (and its direct and indirect
/// components' with `components`), `preview.gif`, `run.json` and `frames.jsonl`.
pub fn run_files(frames: impl IntoIterator<Item = u32>, components: bool) -> BTreeSet<String> {
    let mut files: BTreeSet<String> = ["preview.gif", "run.json", "frames.jsonl"]
        .map(String::from)
        .into();
    let parts: &[&str] = if components {
        &["", "_direct", "_indirect"]
    } else {
        &[""]
    };
    for f in frames {
        let stem = frame_stem(f);
        for part in parts {
            for ext in ["exr", "png"] {
                files.insert(format!("{stem}{part}.{ext}"));
            }
        }
    }
    files
}

fn read_manifest(dir: &Path) -> BTreeSet<String> {
    std::fs::read(dir.join(MANIFEST))
        .ok()
        .and_then(|b| serde_json::from_slice::<Manifest>(&b).ok())
        .map(|m| m.files)
        .unwrap_or_default()
        .into_iter()
        // Names in the folder only: a manifest edited to name other files removes nothing.
        .filter(|n| !n.contains(['/', '\\']) && !n.starts_with('.'))
        .collect()
}

fn write_manifest(dir: &Path, files: &BTreeSet<String>) -> Result<()> {
    let m = Manifest {
        about: "the files irad wrote into this folder; the next irad run here removes them (and no other file)".into(),
        files: files.clone(),
    };
    super::write_json(&dir.join(MANIFEST), &m)
}

/// Prepares `dir` for a run that writes `planned`: creates it and checks it is writable,
/// removes the files an earlier irad run recorded writing there (saying so on stderr), and
/// records `planned` in the manifest. A file of irad's output shapes that no manifest lists
/// is the user's: the run stops naming it, unless `overwrite`, which removes it too.
pub fn prepare_run_dir(dir: &Path, planned: BTreeSet<String>, overwrite: bool) -> Result<RunDir> {
    prepare_out_dir(dir)?;
    remove_stray_temporaries(dir);
    let listed = read_manifest(dir);
    let mut ours = Vec::new();
    let mut foreign = Vec::new();
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot list", dir.display()))?;
    for entry in entries {
        let entry = entry.with_context(|| format!("{}: cannot list", dir.display()))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if !entry.file_type().is_ok_and(|t| t.is_file()) {
            continue;
        }
        // A manifest is a file like any other: only names of irad's output shapes in it count,
        // so an edited or planted manifest cannot make irad remove a user's other files.
        if listed.contains(&name) && is_run_output(&name) {
            ours.push(name);
        } else if is_run_output(&name) {
            foreign.push(name);
        }
    }
    foreign.sort();
    if let Some(first) = foreign.first().filter(|_| !overwrite) {
        let more = match foreign.len() {
            1 => String::new(),
            n => format!(" and {} more such files", n - 1),
        };
        anyhow::bail!(
            "{}: holds {first}{more}, which no earlier irad run recorded writing there (in {MANIFEST}); irad does not delete or replace files it did not write: move them, choose another `out` folder, or pass `overwrite` to replace them",
            dir.display()
        );
    }
    let remove = |name: &String| {
        let path = dir.join(name);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e).with_context(|| {
                format!("{}: cannot remove an earlier run's file", path.display())
            }),
            _ => Ok(()),
        }
    };
    ours.iter().try_for_each(remove)?;
    foreign.iter().try_for_each(remove)?;
    if !ours.is_empty() {
        eprintln!(
            "note: removed {} files of an earlier run from {} (the files its {MANIFEST} lists)",
            ours.len(),
            dir.display()
        );
    }
    if !foreign.is_empty() {
        eprintln!(
            "note: overwrite: removed {} files irad had not recorded writing from {} (from {})",
            foreign.len(),
            dir.display(),
            foreign[0]
        );
    }
    write_manifest(dir, &planned)?;
    Ok(RunDir {
        dir: dir.to_path_buf(),
        planned,
    })
}

/// The file a temporary of irad's is for and the process writing it, when `name` is one
/// (`.NAME.tmp-PID.EXT`, see `image::atomic_write` and `GifStream`).
pub(crate) fn parse_temporary(name: &str) -> Option<(&str, u32)> {
    let (inner, rest) = name.strip_prefix('.')?.split_once(".tmp-")?;
    let pid = rest.split('.').next()?.parse().ok()?;
    Some((inner, pid))
}

/// Whether `name` is one of irad's own temporaries of a run's output file, and of which
/// process.
fn temporary_of(name: &str) -> Option<u32> {
    let (inner, pid) = parse_temporary(name)?;
    (is_run_output(inner) || inner == MANIFEST).then_some(pid)
}

/// Removes the temporaries a run that was killed left in `dir` (not those of a process that
/// is still running, which may be writing them).
fn remove_stray_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = temporary_of(&name) else {
            continue;
        };
        let alive = pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists();
        if !alive && entry.file_type().is_ok_and(|t| t.is_file()) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

impl RunDir {
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Narrows the manifest to the planned files that are there (at the end of a run, or
    /// when it stops early).
    pub fn finish(&self) -> Result<()> {
        let written = self
            .planned
            .iter()
            .filter(|n| self.dir.join(n).is_file())
            .cloned()
            .collect();
        write_manifest(&self.dir, &written)
    }
}
