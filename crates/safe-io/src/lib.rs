//! Files in and out without losing data, for every crate of the workspace
//! that reads inputs or writes results.
//!
//! - [`read_input`] reads a regular file, at most a stated number of bytes,
//!   and refuses anything else (a FIFO would block forever, `/dev/zero`
//!   would fill the memory) with a message naming the path and the fix.
//!   Once a program calls [`protect_inputs`], every file read this way is
//!   remembered as an input of the process.
//! - [`write_atomic`] writes a result: a regular file (or a new name) is
//!   replaced atomically (temporary file, sync, rename), so a reader sees the
//!   old or the new contents and an interrupted write leaves the old ones; a
//!   character device or a FIFO is written into, as `cp` does; a directory,
//!   socket or block device is refused; and a target that is one of the
//!   process's inputs (by any name: relative, through a symbolic link, a
//!   hard link) is refused before a byte is written.
//! - [`check_output`] runs the writer's refusals without writing, so that a
//!   command can refuse its outputs before hours of work rather than after.
#![deny(missing_docs)]

mod inputs;
mod kind;
mod read;
mod write;

pub use inputs::{input_at, protect_inputs, register_input, same_file};
pub use kind::FileKind;
pub use read::{ReadError, read_input, read_regular};
pub use write::{WriteError, check_output, create_parent, write_atomic, write_atomic_with};
