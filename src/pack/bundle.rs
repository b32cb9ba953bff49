//! The FMU library inside the `mbfmu` executable, so that an installed `mbfmu pack` works
//! anywhere (`cargo install` installs no cdylib). `mbfmu install` writes a copy of the
//! executable with the library appended and a trailer — the library's length (u64, little
//! endian) and the magic `MBFMULB1` — which [`embedded_library`] reads back. An ELF,
//! Mach-O or PE loader ignores bytes past the image, as self-extracting archives rely on.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

const MAGIC: &[u8; 8] = b"MBFMULB1";
const TRAILER: u64 = 16;

/// The library appended to the executable file `exe`, if it carries one.
pub fn library_in(exe: &Path) -> Option<Vec<u8>> {
    let mut f = std::fs::File::open(exe).ok()?;
    let len = f.metadata().ok()?.len();
    if len < TRAILER {
        return None;
    }
    f.seek(SeekFrom::Start(len - TRAILER)).ok()?;
    let mut t = [0u8; 16];
    f.read_exact(&mut t).ok()?;
    if &t[8..] != MAGIC {
        return None;
    }
    let n = u64::from_le_bytes(t[..8].try_into().ok()?);
    if n > len - TRAILER {
        return None;
    }
    f.seek(SeekFrom::Start(len - TRAILER - n)).ok()?;
    let mut lib = vec![0u8; usize::try_from(n).ok()?];
    f.read_exact(&mut lib).ok()?;
    Some(lib)
}

/// The library appended to the running executable, if any.
pub fn embedded_library() -> Option<Vec<u8>> {
    library_in(&std::env::current_exe().ok()?)
}

/// The executable image of `exe` without an appended library.
pub fn image(exe: &Path) -> std::io::Result<Vec<u8>> {
    let mut bytes = std::fs::read(exe)?;
    if let Some(lib) = library_in(exe) {
        bytes.truncate(bytes.len() - lib.len() - TRAILER as usize);
    }
    Ok(bytes)
}

/// `image` followed by `lib` and the trailer.
pub fn bundled(image: &[u8], lib: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(image.len() + lib.len() + TRAILER as usize);
    out.extend_from_slice(image);
    out.extend_from_slice(lib);
    out.extend_from_slice(&(lib.len() as u64).to_le_bytes());
    out.extend_from_slice(MAGIC);
    out
}
