//! Peak resident set size of this process, for `lumest bench`: the
//! kernel's high-water mark `VmHWM` in `/proc/self/status`, reset between
//! cases by writing `5` to `/proc/self/clear_refs` (Linux 4.0 and later).
//! Elsewhere both report that they cannot, and the bench prints `n/a`.

/// Reset the peak to the current resident set; false where unsupported.
/// With glibc the heap that earlier cases freed is first given back to
/// the system (`malloc_trim`): kept, it counted in every later case's peak
/// (the 506-point planes case read 100.9 MiB after the office, 7.6 alone).
pub fn reset() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free heap pages to the system; it
    // touches no memory the program holds.
    #[allow(unsafe_code)]
    unsafe {
        libc::malloc_trim(0);
    }
    let ok = std::fs::write("/proc/self/clear_refs", "5").is_ok();
    RESET_HELD.store(ok, std::sync::atomic::Ordering::Relaxed);
    ok
}

/// Whether the last [`reset`] took (true before any): after one that did
/// not, the high-water mark is the whole process's, not the row's.
static RESET_HELD: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(true);

/// Peak resident set size \[bytes\] since the start or the last [`reset`];
/// `None` where unsupported or where the last reset did not take (the
/// bench then prints `n/a`, not the process's peak as the row's; a
/// reviewer's find).
pub fn peak() -> Option<u64> {
    if !RESET_HELD.load(std::sync::atomic::Ordering::Relaxed) {
        return None;
    }
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_hwm(&status)
}

/// The `VmHWM:   1234 kB` line of a `/proc/<pid>/status` text, in bytes.
fn parse_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024)
}

/// A peak \[bytes\] as MiB for a table, or `n/a`.
pub fn format_mib(peak: Option<u64>) -> String {
    peak.map_or_else(
        || "n/a".to_string(),
        |b| format!("{:.1}", b as f64 / (1024.0 * 1024.0)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_high_water_mark() {
        assert_eq!(
            parse_hwm("Name:\tlumest\nVmPeak:\t  9000 kB\nVmHWM:\t    5120 kB\nVmRSS:\t 100 kB\n"),
            Some(5120 * 1024)
        );
        assert_eq!(parse_hwm("VmRSS: 1 kB\n"), None);
        assert_eq!(format_mib(Some(5 << 20)), "5.0");
        assert_eq!(format_mib(None), "n/a");
        // On Linux the process's own peak is there and at least a page.
        if cfg!(target_os = "linux") {
            assert!(peak().is_some_and(|b| b >= 4096));
        }
        // After a reset that did not take, no peak (not the process's).
        RESET_HELD.store(false, std::sync::atomic::Ordering::Relaxed);
        assert_eq!(peak(), None);
        RESET_HELD.store(true, std::sync::atomic::Ordering::Relaxed);
    }
}
