//! One door in, one door out: a command declares every file it reads and writes once, up
//! front, and [`Door::check`] refuses, before any work, whatever would destroy an input, write
//! onto a device or block.
//!
//! - An output that is, or resolves to, an input of the same command (the same spelling,
//!   `./`, an absolute path, a symbolic link or a hard link: compared by device and inode, or
//!   for a file that does not exist yet by its directory's device and inode and its name) is
//!   refused, naming both paths and their roles.
//! - Two outputs that are one file are refused alike (the second would replace the first).
//! - An output that exists and is not a regular file (a device, FIFO, socket or directory)
//!   is refused and left as it is; an output directory must be a directory or absent.
//! - An input that exists and is not a regular file is refused before anything opens it, so
//!   no FIFO can block the command and no device be read.
//!
//! Files a command writes into an output directory (named as it goes) are checked against the
//! inputs with [`Door::check_output_in_dir`] before each is written. The writing itself goes
//! through [`crate::output_file`] (or a store writer); reading through
//! [`crate::input_file`].

use std::ffi::OsString;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};

use crate::error::{Conflict, Result, UtilError};
use crate::input_file::kind;

/// Whether a declared file is read or written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// A file the command reads.
    Input,
    /// A file the command writes.
    Output,
    /// A directory the command writes files into.
    OutputDir,
}

/// One declared file: its role in words ("--output", "SCENE", "the PNG beside --output"),
/// its path as given, and its direction.
#[derive(Clone, Debug)]
pub struct Declared {
    pub role: String,
    pub path: PathBuf,
    pub direction: Direction,
}

/// The files of one command (see the module's docs).
#[derive(Clone, Debug, Default)]
pub struct Door {
    files: Vec<Declared>,
}

impl Door {
    /// A door with nothing declared.
    pub fn new() -> Door {
        Door::default()
    }

    /// Declares `path`, read by the command as `role`.
    pub fn input(&mut self, role: impl Into<String>, path: &Path) -> &mut Door {
        self.declare(role, path, Direction::Input)
    }

    /// Declares `path`, written by the command as `role`.
    pub fn output(&mut self, role: impl Into<String>, path: &Path) -> &mut Door {
        self.declare(role, path, Direction::Output)
    }

    /// Declares the directory `dir`, which the command writes files into as `role`.
    pub fn output_dir(&mut self, role: impl Into<String>, dir: &Path) -> &mut Door {
        self.declare(role, dir, Direction::OutputDir)
    }

    fn declare(&mut self, role: impl Into<String>, path: &Path, direction: Direction) -> &mut Door {
        self.files.push(Declared {
            role: role.into(),
            path: path.to_path_buf(),
            direction,
        });
        self
    }

    /// Everything declared, in the order it was.
    pub fn declared(&self) -> &[Declared] {
        &self.files
    }

    /// Checks every declared file (see the module's docs). Changes nothing.
    pub fn check(&self) -> Result<()> {
        for f in &self.files {
            match f.direction {
                Direction::Input => check_input(f)?,
                Direction::Output => check_output(f)?,
                Direction::OutputDir => check_output_dir(f)?,
            }
        }
        let ids: Vec<Option<Identity>> = self.files.iter().map(|f| identity(&f.path)).collect();
        for (i, out) in self.files.iter().enumerate() {
            if out.direction == Direction::Input {
                continue;
            }
            for (j, other) in self.files.iter().enumerate() {
                if i == j || ids[i].is_none() || ids[i] != ids[j] {
                    continue;
                }
                match other.direction {
                    Direction::Input => return Err(output_is_input(out, other)),
                    // Each pair once, the first declared named first.
                    _ if j > i => return Err(UtilError::SameOutput(conflict(out, other))),
                    _ => {}
                }
            }
        }
        Ok(())
    }

    /// Checks a file `path` that the command is about to write into one of its output
    /// directories, as `role`: it may be no declared input and no other declared output, and
    /// must be absent or a regular file.
    pub fn check_output_in_dir(&self, role: impl Into<String>, path: &Path) -> Result<()> {
        let out = Declared {
            role: role.into(),
            path: path.to_path_buf(),
            direction: Direction::Output,
        };
        check_output(&out)?;
        let Some(id) = identity(path) else {
            return Ok(());
        };
        for f in &self.files {
            if f.direction == Direction::OutputDir || identity(&f.path).as_ref() != Some(&id) {
                continue;
            }
            return Err(match f.direction {
                Direction::Input => output_is_input(&out, f),
                _ => UtilError::SameOutput(conflict(f, &out)),
            });
        }
        Ok(())
    }
}

fn output_is_input(out: &Declared, input: &Declared) -> UtilError {
    UtilError::OutputIsInput(conflict(out, input))
}

fn conflict(first: &Declared, second: &Declared) -> Box<Conflict> {
    Box::new(Conflict {
        first_role: first.role.clone(),
        first: first.path.clone(),
        second_role: second.role.clone(),
        second: second.path.clone(),
    })
}

/// An input that exists must be a regular file (a missing one is left to its reader, which
/// says so in its own words).
fn check_input(f: &Declared) -> Result<()> {
    match std::fs::metadata(&f.path) {
        Ok(m) if !m.is_file() => Err(UtilError::NotRegular {
            path: f.path.clone(),
            kind: kind(&m.file_type()),
        }),
        _ => Ok(()),
    }
}

fn check_output(f: &Declared) -> Result<()> {
    crate::output_file::check_target(&f.path).map_err(|e| match e {
        UtilError::OutputNotRegular { path, kind, .. } => UtilError::OutputNotRegular {
            role: f.role.clone(),
            path,
            kind,
        },
        e => e,
    })
}

fn check_output_dir(f: &Declared) -> Result<()> {
    match std::fs::metadata(&f.path) {
        Ok(m) if !m.is_dir() => Err(UtilError::OutputNotDirectory {
            role: f.role.clone(),
            path: f.path.clone(),
            kind: if m.is_file() {
                "a regular file"
            } else {
                kind(&m.file_type())
            },
        }),
        _ => Ok(()),
    }
}

/// What makes two paths one file.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Identity {
    /// An existing file: its device and inode (symbolic links followed).
    File(u64, u64),
    /// A file not there yet: its directory's device and inode, and its name.
    New(u64, u64, OsString),
}

fn identity(path: &Path) -> Option<Identity> {
    match std::fs::metadata(path) {
        Ok(m) => Some(Identity::File(dev(&m), ino(&m))),
        Err(e) if e.kind() == ErrorKind::NotFound => {
            // A dangling symbolic link: the file it names.
            let path = crate::output_file::resolve_dangling(path);
            let name = path.file_name()?.to_os_string();
            let dir = match path.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            };
            let d = std::fs::metadata(dir).ok()?;
            Some(Identity::New(dev(&d), ino(&d), name))
        }
        Err(_) => None,
    }
}

#[cfg(unix)]
fn dev(m: &std::fs::Metadata) -> u64 {
    std::os::unix::fs::MetadataExt::dev(m)
}

#[cfg(unix)]
fn ino(m: &std::fs::Metadata) -> u64 {
    std::os::unix::fs::MetadataExt::ino(m)
}

#[cfg(not(unix))]
fn dev(_: &std::fs::Metadata) -> u64 {
    0
}

#[cfg(not(unix))]
fn ino(_: &std::fs::Metadata) -> u64 {
    0
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn outputs_over_inputs_are_refused_however_spelled() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let input = dir.join("scene.toml");
        std::fs::write(&input, b"x").unwrap();
        let hard = dir.join("hard.toml");
        std::fs::hard_link(&input, &hard).unwrap();
        let soft = dir.join("soft.toml");
        std::os::unix::fs::symlink("scene.toml", &soft).unwrap();
        std::fs::create_dir(dir.join("sub")).unwrap();
        for out in [
            input.clone(),
            dir.join(".").join("scene.toml"),
            dir.join("sub/../scene.toml"),
            hard,
            soft,
        ] {
            let e = Door::new()
                .input("SCENE", &input)
                .output("--output", &out)
                .check()
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(&format!("--output {}", out.display()))
                    && e.contains(&format!("SCENE {}", input.display()))
                    && e.contains("the same file"),
                "{e}"
            );
        }
        Door::new()
            .input("SCENE", &input)
            .output("--output", &dir.join("other.oslf"))
            .check()
            .unwrap();
    }

    #[test]
    fn two_outputs_that_are_one_file_are_refused_even_before_either_exists() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let a = dir.join("out.oslf");
        let e = Door::new()
            .output("--output", &a)
            .output("--report-json", &dir.join(".").join("out.oslf"))
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("--output") && e.contains("--report-json"), "{e}");
        assert!(!a.exists());
    }

    #[test]
    fn nodes_and_directories_are_refused_on_either_side() {
        use rustix::fs::{mkfifoat, Mode, CWD};
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let fifo = dir.join("f");
        mkfifoat(CWD, &fifo, Mode::from_raw_mode(0o600)).unwrap();
        let e = Door::new()
            .input("STORE", &fifo)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("(a FIFO)"), "{e}");
        let e = Door::new()
            .output("--output", &fifo)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("--output") && e.contains("(a FIFO)"), "{e}");
        let e = Door::new()
            .output("--output", dir)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("(a directory)"), "{e}");
        let file = dir.join("file");
        std::fs::write(&file, b"x").unwrap();
        let e = Door::new()
            .output_dir("--out", &file)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a directory"), "{e}");
        // Files named as a command goes, inside its output directory.
        let mut door = Door::new();
        door.input("--store", &file).output_dir("--out", dir);
        door.check().unwrap();
        let e = door
            .check_output_in_dir("a table", &dir.join("./file"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("--store") && e.contains("a table"), "{e}");
        door.check_output_in_dir("a table", &dir.join("t.csv"))
            .unwrap();
    }
}
