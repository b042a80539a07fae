//! Sealed shared memory: anonymous files (`memfd_create`) whose size nobody can change, handed
//! to child processes as inherited file descriptors.
//!
//! A file in /dev/shm can be opened by name and truncated by any process of the user: a mapping
//! of it then raises SIGBUS in every reader. A memfd has no name to open, and its seals
//! (`fcntl(F_ADD_SEALS)`) hold for every descriptor of it, even one opened again through
//! `/proc/<pid>/fd/<n>`: `F_SEAL_SHRINK | F_SEAL_GROW` fix its size, `F_SEAL_FUTURE_WRITE`
//! refuses every new writable mapping and every `write()` (the mappings made before stay
//! writable), and `F_SEAL_SEAL` refuses any further seal (nobody can add `F_SEAL_FUTURE_WRITE`
//! to a file others must still map writable). The reader checks the seals with
//! `fcntl(F_GET_SEALS)` before it maps anything.

use rustix::fs::{MemfdFlags, SealFlags};
use rustix::mm::{MapFlags, ProtFlags};
use std::os::fd::{AsRawFd, BorrowedFd, OwnedFd, RawFd};

/// The seals every segment of the runtime carries from its creation on: its size is fixed.
pub const SIZE_SEALS: SealFlags = SealFlags::SHRINK.union(SealFlags::GROW);

/// Why a sealed segment could not be made, checked or mapped.
#[derive(Debug, thiserror::Error)]
pub enum SealError {
    #[error("memfd_create({name}): {source}")]
    Create {
        name: String,
        source: std::io::Error,
    },
    #[error("seal the segment {name} (fd {fd}): {source}")]
    Seal {
        name: String,
        fd: RawFd,
        source: std::io::Error,
    },
    /// The descriptor is not a sealed memfd (a file of /dev/shm, or a memfd someone could
    /// still resize or map writable): refused before anything is mapped.
    #[error("the segment {name} (fd {fd}) lacks the seals {missing:?} (it has {has:?})")]
    Unsealed {
        name: String,
        fd: RawFd,
        missing: SealFlags,
        has: SealFlags,
    },
    #[error("map the segment {name} (fd {fd}): {source}")]
    Map {
        name: String,
        fd: RawFd,
        source: std::io::Error,
    },
}

/// Makes a memfd of `len` zero bytes named `name` (shown in /proc/<pid>/fd as
/// `/memfd:<name>`), close-on-exec, its size sealed.
pub fn create(name: &str, len: usize) -> Result<OwnedFd, SealError> {
    let fd = rustix::fs::memfd_create(name, MemfdFlags::CLOEXEC | MemfdFlags::ALLOW_SEALING)
        .map_err(|e| SealError::Create {
            name: name.to_string(),
            source: e.into(),
        })?;
    let seal_error = |fd: &OwnedFd, e: rustix::io::Errno| SealError::Seal {
        name: name.to_string(),
        fd: fd.as_raw_fd(),
        source: e.into(),
    };
    rustix::fs::ftruncate(&fd, len as u64).map_err(|e| seal_error(&fd, e))?;
    rustix::fs::fcntl_add_seals(&fd, SIZE_SEALS).map_err(|e| seal_error(&fd, e))?;
    Ok(fd)
}

/// Adds `seals` to the memfd `fd`.
pub fn seal(fd: BorrowedFd, name: &str, seals: SealFlags) -> Result<(), SealError> {
    rustix::fs::fcntl_add_seals(fd, seals).map_err(|e| SealError::Seal {
        name: name.to_string(),
        fd: fd.as_raw_fd(),
        source: e.into(),
    })
}

/// The segment's length, if `fd` carries every seal of `required` (refused otherwise).
pub fn check(fd: BorrowedFd, name: &str, required: SealFlags) -> Result<usize, SealError> {
    let raw = fd.as_raw_fd();
    let has = rustix::fs::fcntl_get_seals(fd).unwrap_or(SealFlags::empty());
    if !has.contains(required) {
        return Err(SealError::Unsealed {
            name: name.to_string(),
            fd: raw,
            missing: required.difference(has),
            has,
        });
    }
    let st = rustix::fs::fstat(fd).map_err(|e| SealError::Map {
        name: name.to_string(),
        fd: raw,
        source: e.into(),
    })?;
    Ok(st.st_size as usize)
}

/// A shared mapping of a whole sealed segment.
pub struct Mapping {
    base: *mut u8,
    len: usize,
}

// SAFETY: the mapping is plain shared memory; its users access it through atomics.
unsafe impl Send for Mapping {}
unsafe impl Sync for Mapping {}

impl Mapping {
    /// Maps `len` bytes of `fd` shared, writable or read-only. A read-only mapping of a file
    /// sealed `F_SEAL_FUTURE_WRITE` can never be made writable (`mprotect` is refused).
    pub fn map(fd: BorrowedFd, name: &str, len: usize, writable: bool) -> Result<Self, SealError> {
        if len == 0 {
            return Ok(Mapping {
                base: std::ptr::NonNull::<u64>::dangling().as_ptr() as *mut u8,
                len: 0,
            });
        }
        let prot = if writable {
            ProtFlags::READ | ProtFlags::WRITE
        } else {
            ProtFlags::READ
        };
        // SAFETY: a new mapping chosen by the kernel; it is unmapped only in Drop.
        let p =
            unsafe { rustix::mm::mmap(std::ptr::null_mut(), len, prot, MapFlags::SHARED, fd, 0) }
                .map_err(|e| SealError::Map {
                name: name.to_string(),
                fd: fd.as_raw_fd(),
                source: e.into(),
            })?;
        Ok(Mapping {
            base: p as *mut u8,
            len,
        })
    }

    pub fn base(&self) -> *mut u8 {
        self.base
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl Drop for Mapping {
    fn drop(&mut self) {
        if self.len > 0 {
            // SAFETY: unmapping our own mapping.
            let _ = unsafe { rustix::mm::munmap(self.base as *mut _, self.len) };
        }
    }
}

/// Makes `cmd`'s child inherit `fds` (which are close-on-exec in this process, so no other
/// child gets them): their numbers stay the same in the child.
pub fn pass_to(cmd: &mut std::process::Command, fds: &[RawFd]) {
    use std::os::unix::process::CommandExt;
    let fds = fds.to_vec();
    // SAFETY: the closure runs between fork and exec and only calls fcntl, which is
    // async-signal-safe; it allocates nothing.
    unsafe {
        cmd.pre_exec(move || {
            for &fd in &fds {
                if libc::fcntl(fd, libc::F_SETFD, 0) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
            }
            Ok(())
        });
    }
}

/// The inherited descriptor `fd` (named by an environment variable the parent set), if it is
/// open. It is borrowed for the whole life of the process: nothing here closes it, so it can be
/// mapped again (an agent's second look at the barrier after an error).
pub fn inherited(fd: RawFd) -> Option<BorrowedFd<'static>> {
    // SAFETY: F_GETFD only asks whether fd is open.
    if fd < 0 || unsafe { libc::fcntl(fd, libc::F_GETFD) } < 0 {
        return None;
    }
    // SAFETY: fd is open and, handed to this process by its parent, never closed by it.
    Some(unsafe { BorrowedFd::borrow_raw(fd) })
}
