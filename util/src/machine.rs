//! What the machine offers: memory for new allocations and free space on a volume, for the
//! bake's preflight and the renderer's cache sizing. Each is `None` where it cannot be known;
//! callers then skip the check rather than guess.

use std::path::Path;

/// Bytes available for new allocations: `MemAvailable` of /proc/meminfo on Linux. `None`
/// elsewhere, or if it cannot be read: then memory is not checked.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_meminfo(&text)
}

/// `MemAvailable` of a /proc/meminfo text, in bytes.
pub fn parse_meminfo(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let mut words = line.split_whitespace().skip(1);
    let kib: u64 = words.next()?.parse().ok()?;
    match words.next() {
        Some("kB") | None => kib.checked_mul(1024),
        Some(_) => None,
    }
}

/// Bytes free for an unprivileged user on the volume holding `dir` (statvfs: `f_bavail` ×
/// `f_frsize`). `None` where unknown (not Unix, or the call failed): then space is not checked.
pub fn free_space(dir: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let s = rustix::fs::statvfs(dir).ok()?;
        Some(s.f_bavail.saturating_mul(s.f_frsize))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meminfo_gives_available_bytes_or_nothing() {
        let text = "MemTotal:       24000000 kB\nMemFree:  1000 kB\nMemAvailable:   18200000 kB\n";
        assert_eq!(parse_meminfo(text), Some(18_200_000 * 1024));
        assert_eq!(parse_meminfo("MemTotal: 1 kB\n"), None);
        assert_eq!(parse_meminfo("MemAvailable: 5 MB\n"), None);
        assert_eq!(parse_meminfo("MemAvailable: x kB\n"), None);
        assert_eq!(
            parse_meminfo("MemAvailable: 18446744073709551615 kB\n"),
            None
        );
    }

    #[test]
    fn this_machine_reports_memory_and_space() {
        if cfg!(target_os = "linux") {
            assert!(available_memory().is_some_and(|b| b > 0));
            assert!(free_space(Path::new(".")).is_some());
        }
        assert_eq!(free_space(Path::new("/no/such/directory/here")), None);
    }
}
