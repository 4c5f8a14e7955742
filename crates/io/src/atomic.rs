//! Files written whole or not at all: to a temporary name beside the
//! target (`.<name>.tmp<process id>`), then renamed over it (atomic on one
//! file system). A writer killed between the two leaves its temporary
//! behind; [`remove_temporaries`] clears them once no writer is left.

use std::fs;
use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically.
pub fn write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::other(format!("{} has no file name", path.display())))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp{}", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Whether `name` is a temporary of [`write()`]: `.<name>.tmp<digits>`.
pub fn is_temporary(name: &str) -> bool {
    name.strip_prefix('.')
        .and_then(|rest| rest.rsplit_once(".tmp"))
        .is_some_and(|(target, pid)| {
            !target.is_empty() && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())
        })
}

/// Removes the temporaries [`write()`] left in `dir` (not in its
/// subfolders), returning how many. Only for a folder no one else is
/// writing into (the caller holds its lock): a live writer's temporary
/// would go too.
pub fn remove_temporaries(dir: &Path) -> std::io::Result<usize> {
    let mut removed = 0;
    for entry in fs::read_dir(dir)? {
        let entry = entry?;
        if entry.file_name().to_str().is_some_and(is_temporary) && entry.file_type()?.is_file() {
            match fs::remove_file(entry.path()) {
                Ok(()) => removed += 1,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(e),
            }
        }
    }
    Ok(removed)
}

#[cfg(test)]
mod tests {
    #[test]
    fn temporaries_are_recognised_and_removed() {
        use super::{is_temporary, remove_temporaries};
        assert!(is_temporary(".summary.json.tmp1234"));
        assert!(is_temporary(".frame_00001.vtu.tmp7"));
        assert!(!is_temporary("summary.json"));
        assert!(!is_temporary(".summary.json.tmp"));
        assert!(!is_temporary(".summary.json.tmp12a"));
        assert!(!is_temporary(".tmp12"));
        assert!(!is_temporary(".drape.lock"));
        let dir = std::env::temp_dir().join(format!("drape-tmps-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in [".a.csv.tmp99", "a.csv", ".b.vtu.tmp1", ".keep"] {
            std::fs::write(dir.join(name), b"x").unwrap();
        }
        assert_eq!(remove_temporaries(&dir).unwrap(), 2);
        let mut left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        assert_eq!(left, [".keep", "a.csv"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn writes_whole_file_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("drape-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.txt");
        super::write(&path, b"first").unwrap();
        super::write(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
