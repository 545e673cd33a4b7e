//! Every file clothlab writes goes through here: written to a temporary file beside the
//! target and renamed over it only when complete, so a run that fails or is interrupted
//! (Ctrl-C, `kill`, a full disk) leaves the file that was there before as it was.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

/// The temporary file beside `path`: hidden, named after the target and this process.
fn temporary(path: &Path) -> Result<PathBuf> {
    let name = path.file_name().with_context(|| format!("{}: not a file name", path.display()))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    Ok(dir.join(format!(".{}.{}.tmp", name.to_string_lossy(), std::process::id())))
}

/// Fails, in one line, where `path` could not be written at the end of a run: its folder
/// is missing or not writable, or it is a folder. Touches no existing file (a temporary
/// one is made beside it and removed).
pub fn check_writable(path: &Path) -> Result<()> {
    if path.is_dir() {
        bail!("cannot write {}: it is a folder", path.display());
    }
    let tmp = temporary(path)?;
    File::create(&tmp).with_context(|| format!("cannot write {}", path.display()))?;
    std::fs::remove_file(&tmp).ok();
    Ok(())
}

/// Writes `path` through `write`, atomically: nothing at `path` changes unless all of it
/// was written and synced.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>) -> Result<()> {
    let tmp = temporary(path)?;
    let result = (|| -> io::Result<()> {
        let mut w = BufWriter::new(File::create(&tmp)?);
        write(&mut w)?;
        w.flush()?;
        w.get_ref().sync_all()?;
        drop(w);
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        std::fs::remove_file(&tmp).ok();
        return Err(e).with_context(|| format!("cannot write {}", path.display()));
    }
    Ok(())
}

/// [`write_atomic`] of bytes.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
}

/// An RGBA8 image as PNG, atomically.
pub fn write_png(path: &Path, rgba: &[u8], width: u32, height: u32) -> Result<()> {
    let mut png = Vec::new();
    image::write_buffer_with_format(
        &mut io::Cursor::new(&mut png),
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
        image::ImageFormat::Png,
    )
    .with_context(|| format!("cannot encode {}", path.display()))?;
    write_bytes(path, &png)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = std::env::temp_dir().join(format!("clothlab-files-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.json");
        std::fs::write(&path, "old").unwrap();
        check_writable(&path).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old", "checking touches nothing");
        let e = write_atomic(&path, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("disk full"))
        })
        .unwrap_err();
        assert!(format!("{e:#}").contains("disk full"), "{e:#}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        write_bytes(&path, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left.len(), 1, "no temporary file left: {left:?}");
        assert!(check_writable(&dir).unwrap_err().to_string().contains("is a folder"));
        assert!(check_writable(&dir.join("missing/x.json")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
