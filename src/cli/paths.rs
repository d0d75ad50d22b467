//! The types of every path the command line takes, so that each is declared, by its type, as
//! read or written: [`InputPath`] (a file the command reads), [`OutputPath`] (a file it
//! writes), [`OutputDir`] (a directory it writes files into). Each command hands them to its
//! [`Door`](oslf_util::door::Door) before any work; the door test derives the list of flags to
//! try from these types in the clap definition, so a path flag of another type fails it.

use std::ffi::OsString;
use std::ops::Deref;
use std::path::{Path, PathBuf};

macro_rules! path_type {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Debug, PartialEq, Eq)]
        pub struct $name(pub PathBuf);

        impl From<OsString> for $name {
            fn from(s: OsString) -> Self {
                $name(PathBuf::from(s))
            }
        }

        impl Deref for $name {
            type Target = Path;
            fn deref(&self) -> &Path {
                &self.0
            }
        }

        impl AsRef<Path> for $name {
            fn as_ref(&self) -> &Path {
                &self.0
            }
        }
    };
}

path_type!(
    /// A file the command reads.
    InputPath
);
path_type!(
    /// A file the command writes.
    OutputPath
);
path_type!(
    /// A directory the command writes files into.
    OutputDir
);
path_type!(
    /// The start of the names of files the command writes (`PREFIX-MODE.exr`).
    OutputPrefix
);

/// Declares the files `scene` was read from as inputs of `door`: the scene file as `role`,
/// then each file it includes.
pub fn declare_scene(
    door: &mut oslf_util::door::Door,
    role: &str,
    scene: &oslf_scene::scene::Scene,
) {
    for (i, file) in scene.files.iter().enumerate() {
        if i == 0 {
            door.input(role, file);
        } else {
            door.input(format!("a file {role} includes"), file);
        }
    }
}
