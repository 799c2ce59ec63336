//! Output paths checked before a run: every output can be written, none
//! overwrites an input, and no two outputs are the same file.
//!
//! Paths are compared where the write lands: the canonical folder joined
//! with the file name (an atomic write renames onto that name), and, for a
//! file that exists, its canonical path (symbolic links resolved).

use anyhow::Context;
use std::path::{Path, PathBuf};

/// The paths a file name stands for: where a write to it lands, and the
/// file it resolves to when it exists.
fn identities(path: &Path) -> Vec<PathBuf> {
    let mut ids = Vec::new();
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if let (Ok(d), Some(name)) = (dir.canonicalize(), path.file_name()) {
        ids.push(d.join(name));
    }
    if let Ok(c) = path.canonicalize() {
        ids.push(c);
    }
    ids
}

/// Check the outputs of a run before it starts. `inputs` are the files the
/// run reads; `outputs` pairs each output path with the option that names
/// it. `-` (standard input or output) is never a file; two outputs on
/// standard output are refused (their texts would mix).
///
/// Each output's folder must exist and take a new file (a temporary file is
/// created there and removed, as the atomic write will do), the output must
/// not be a folder, and it must differ from every input and every other
/// output.
pub fn check_outputs(inputs: &[&Path], outputs: &[(&str, &Path)]) -> anyhow::Result<()> {
    let input_ids: Vec<(PathBuf, &Path)> = inputs
        .iter()
        .filter(|p| p.as_os_str() != "-")
        .flat_map(|&p| identities(p).into_iter().map(move |id| (id, p)))
        .collect();
    let mut seen: Vec<(PathBuf, &str)> = Vec::new();
    let mut stdout: Option<&str> = None;
    for &(opt, path) in outputs {
        if path.as_os_str() == "-" {
            if let Some(first) = stdout {
                anyhow::bail!(
                    "{first} and {opt} both write to standard output (`-`); give one a file"
                );
            }
            stdout = Some(opt);
            continue;
        }
        let shown = path.display();
        anyhow::ensure!(
            !path.is_dir(),
            "{opt} {shown}: is a folder; give a file name"
        );
        // Where the write lands: through symbolic links to their file.
        let landing = crate::io::csvio::through_links(path);
        let dir = landing
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        anyhow::ensure!(
            dir.is_dir(),
            "{opt} {shown}: the folder {} does not exist",
            dir.display()
        );
        let probe = crate::io::csvio::temp_path(&landing);
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&probe)
            .with_context(|| {
                format!(
                    "{opt} {shown}: cannot write in the folder {}",
                    dir.display()
                )
            })?;
        let _ = std::fs::remove_file(&probe);
        let mut ids = identities(path);
        ids.dedup();
        for id in &ids {
            if let Some((_, input)) = input_ids.iter().find(|(i, _)| i == id) {
                anyhow::bail!(
                    "{opt} {shown} would overwrite the input {}; write the output elsewhere",
                    input.display()
                );
            }
            if let Some((_, other)) = seen.iter().find(|(s, _)| s == id) {
                anyhow::bail!(
                    "{opt} {shown} is the same file as {other}; give each output its own file"
                );
            }
        }
        seen.extend(ids.into_iter().map(|id| (id, opt)));
    }
    Ok(())
}
