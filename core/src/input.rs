//! Reading the files a user names (scene files, and meshes once they exist) with a cap on
//! their size: a path that never ends (`/dev/zero`, a FIFO someone keeps writing) must
//! get one line, not a process that grows until the machine runs out of memory.

use std::io::Read;
use std::path::Path;

/// The most bytes a scene file may have. The scenes in `scenes/` are under 3 KiB; a
/// scene that lists every pinned particle of a 1024 × 1024 grid by hand is about 12 MiB
/// (`[i, j]` pairs), so 16 MiB refuses nothing a person writes and bounds the rest.
pub const SCENE_FILE_MAX_BYTES: u64 = 16 << 20;

/// The text of `path`, or why not: it cannot be opened or read, it is not UTF-8, or it
/// has more than `max_bytes` (read no further than one byte past the cap).
pub fn read_text_capped(path: &Path, max_bytes: u64) -> Result<String, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read: {e}"))?;
    let mut bytes = Vec::new();
    file.take(max_bytes + 1).read_to_end(&mut bytes).map_err(|e| format!("cannot read: {e}"))?;
    if bytes.len() as u64 > max_bytes {
        return Err(format!("larger than {} MiB: not read further", max_bytes >> 20));
    }
    String::from_utf8(bytes).map_err(|e| format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_past_the_cap_is_refused_after_reading_one_byte_more() {
        let dir = std::env::temp_dir().join(format!("clothlab-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("x.toml");
        std::fs::write(&path, "a".repeat(1 << 20)).unwrap();
        assert_eq!(read_text_capped(&path, 1 << 20).unwrap().len(), 1 << 20, "exactly the cap is read");
        let e = read_text_capped(&path, (1 << 20) - 1).unwrap_err();
        assert!(e.contains("larger than 0 MiB"), "{e}");
        std::fs::write(&path, [0xffu8, 0xfe]).unwrap();
        assert!(read_text_capped(&path, 16).unwrap_err().contains("not UTF-8"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_file_that_never_ends_is_refused() {
        let e = read_text_capped(Path::new("/dev/zero"), SCENE_FILE_MAX_BYTES).unwrap_err();
        assert_eq!(e, "larger than 16 MiB: not read further");
    }
}
