//! Finding and removing what a run leaves in /dev/shm and in iceoryx2's folders.

use std::path::Path;

/// Names in /dev/shm that belong to the run with this prefix.
pub fn shm_files(prefix: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(prefix))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// Removes every /dev/shm file and the iceoryx2 root folder of the run. Returns how many
/// /dev/shm files it removed.
pub fn remove_run(prefix: &str) -> usize {
    let files = shm_files(prefix);
    for f in &files {
        let p = Path::new("/dev/shm").join(f);
        if p.is_dir() {
            let _ = std::fs::remove_dir_all(&p);
        } else {
            let _ = std::fs::remove_file(&p);
        }
    }
    let _ = std::fs::remove_dir_all(crate::transport::root_for(prefix));
    files.len()
}
