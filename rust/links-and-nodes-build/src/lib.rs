//! For a crate's `build.rs`: generates the Rust types of links_and_nodes message definitions
//! with `ln_generate --lang rust` and tells cargo when to run again (docs/rust.md).
//!
//! ```no_run
//! let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").unwrap());
//! links_and_nodes_build::Generator::new()
//!     .md_dir("md")
//!     .message("robot/joint_state")
//!     .generate(out.join("messages.rs"))
//!     .unwrap();
//! ```
//!
//! ln_generate is found as: the command in `$LN_GENERATE` (split at whitespace, e.g.
//! `python3 -m ln_generate`), else `ln_generate` on `PATH`, else `python3 -m ln_generate`.

use std::env;
use std::ffi::OsString;
use std::fmt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Why generating failed; `Display` is the whole explanation, ready for a build log.
#[derive(Debug)]
pub enum Error {
    /// No ln_generate could be started: every command tried, with why it failed.
    NotFound(Vec<(String, String)>),
    /// ln_generate ran and failed (exit status and its stderr: `file:line:col: message`).
    Failed {
        command: String,
        status: String,
        stderr: String,
    },
    /// Nothing to generate, or an md name that is not one.
    Usage(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NotFound(tried) => {
                writeln!(f, "ln_generate was not found; tried:")?;
                for (cmd, why) in tried {
                    writeln!(f, "  {cmd}: {why}")?;
                }
                write!(
                    f,
                    "install links_and_nodes (python3 -m pip install links_and_nodes), put \
                     ln_generate on PATH, or set LN_GENERATE to the command to run"
                )
            }
            Error::Failed {
                command,
                status,
                stderr,
            } => {
                write!(f, "{command} failed ({status}):\n{}", stderr.trim_end())
            }
            Error::Usage(text) => f.write_str(text),
        }
    }
}

impl std::error::Error for Error {}

/// What to generate: md directories and md names (with their imports) into one Rust file.
#[derive(Debug, Clone, Default)]
pub struct Generator {
    md_dirs: Vec<PathBuf>,
    messages: Vec<String>,
    command: Option<Vec<OsString>>,
    cargo_output: bool,
}

impl Generator {
    /// No md directories, no messages; prints `cargo:` lines (see [`Generator::cargo_output`]).
    pub fn new() -> Generator {
        Generator {
            cargo_output: true,
            ..Generator::default()
        }
    }

    /// Looks definitions up in `dir` first (repeatable; relative to the crate's directory,
    /// where cargo runs build scripts).
    pub fn md_dir(mut self, dir: impl AsRef<Path>) -> Generator {
        self.md_dirs.push(dir.as_ref().to_path_buf());
        self
    }

    /// Generates md `name` (e.g. "robot/joint_state") and what it imports.
    pub fn message(mut self, name: &str) -> Generator {
        self.messages.push(name.to_string());
        self
    }

    /// Runs this command instead of looking for ln_generate (program and leading arguments).
    pub fn command<I: IntoIterator<Item = S>, S: Into<OsString>>(mut self, argv: I) -> Generator {
        self.command = Some(argv.into_iter().map(Into::into).collect());
        self
    }

    /// Whether to print `cargo:rerun-if-changed` / `rerun-if-env-changed` (default true).
    pub fn cargo_output(mut self, on: bool) -> Generator {
        self.cargo_output = on;
        self
    }

    fn candidates(&self) -> Vec<Vec<OsString>> {
        if let Some(c) = &self.command {
            return vec![c.clone()];
        }
        if let Some(v) = env::var_os("LN_GENERATE") {
            let words: Vec<OsString> = v
                .to_string_lossy()
                .split_whitespace()
                .map(OsString::from)
                .collect();
            if !words.is_empty() {
                return vec![words];
            }
        }
        vec![
            vec!["ln_generate".into()],
            vec!["python3".into(), "-m".into(), "ln_generate".into()],
        ]
    }

    fn run(&self, args: &[OsString]) -> Result<(String, Output), Error> {
        let mut tried = Vec::new();
        for argv in self.candidates() {
            let shown = argv
                .iter()
                .map(|a| a.to_string_lossy())
                .collect::<Vec<_>>()
                .join(" ");
            let mut cmd = Command::new(&argv[0]);
            cmd.args(&argv[1..]).args(args);
            match cmd.output() {
                // `python3 -m ln_generate` without the package: try the next, say why.
                Ok(out) if is_missing_module(&out) => tried.push((
                    shown,
                    String::from_utf8_lossy(&out.stderr).trim().to_string(),
                )),
                Ok(out) => return Ok((shown, out)),
                Err(e) => tried.push((shown, e.to_string())),
            }
        }
        Err(Error::NotFound(tried))
    }

    fn base_args(&self) -> Vec<OsString> {
        let mut args = Vec::new();
        for d in &self.md_dirs {
            args.push("--md-dir".into());
            args.push(d.clone().into_os_string());
        }
        args
    }

    /// Writes the Rust types to `output` (only when its content changes) and prints
    /// `cargo:rerun-if-changed` for every md file used.
    pub fn generate(&self, output: impl AsRef<Path>) -> Result<(), Error> {
        if self.messages.is_empty() {
            return Err(Error::Usage(
                "links_and_nodes_build: no message given".into(),
            ));
        }
        if let Some(bad) = self.messages.iter().find(|m| m.starts_with('-')) {
            return Err(Error::Usage(format!(
                "links_and_nodes_build: bad md name {bad:?}"
            )));
        }
        if self.cargo_output {
            println!("cargo:rerun-if-env-changed=LN_GENERATE");
            println!("cargo:rerun-if-env-changed=LN_MESSAGE_DEFINITION_DIRS");
        }
        let mut args = self.base_args();
        args.extend(["--lang".into(), "rust".into(), "-o".into()]);
        args.push(output.as_ref().as_os_str().to_owned());
        args.extend(self.messages.iter().map(OsString::from));
        let (shown, out) = self.run(&args)?;
        check(&shown, &out)?;
        let mut args = self.base_args();
        args.push("--print-deps".into());
        args.extend(self.messages.iter().map(OsString::from));
        let (shown, deps) = self.run(&args)?;
        check(&shown, &deps)?;
        if self.cargo_output {
            for dir in &self.md_dirs {
                println!("cargo:rerun-if-changed={}", dir.display());
            }
            for line in String::from_utf8_lossy(&deps.stdout).lines() {
                println!("cargo:rerun-if-changed={line}");
            }
        }
        Ok(())
    }
}

fn is_missing_module(out: &Output) -> bool {
    !out.status.success()
        && String::from_utf8_lossy(&out.stderr).contains("No module named ln_generate")
}

fn check(shown: &str, out: &Output) -> Result<(), Error> {
    if out.status.success() {
        return Ok(());
    }
    Err(Error::Failed {
        command: shown.to_string(),
        status: out.status.to_string(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    })
}
