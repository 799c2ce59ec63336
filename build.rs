//! Names the build in run states (shards, checkpoints): the git commit, with
//! `+dirty` where tracked files differ from it, or `unknown` outside a git
//! checkout. States of different builds are different runs: their numbers
//! need not agree bit for bit.

use std::process::Command;

fn main() {
    for path in ["build.rs", "src", ".git/HEAD", ".git/index"] {
        println!("cargo:rerun-if-changed={path}");
    }
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let id = match (
        git(&["rev-parse", "HEAD"]),
        git(&["status", "--porcelain", "--untracked-files=no"]),
    ) {
        (Some(commit), Some(changes)) if !changes.is_empty() => format!("{commit}+dirty"),
        (Some(commit), _) => commit,
        _ => "unknown".to_string(),
    };
    println!("cargo:rustc-env=LUMEST_BUILD={id}");
}
