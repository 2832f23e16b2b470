//! The output folder of `coupler-node run`: created when missing, refused when it holds anything
//! unless `--overwrite`, which clears the files an earlier run wrote (and only those), so that no
//! stale output (a `fluid_3.vti` of a run with more outputs) is left beside the new ones.

use std::fs::{File, TryLockError};
use std::path::Path;

use anyhow::Context;

/// The exclusive lock of an output folder, held for the whole run ([`lock`]); dropped, the
/// kernel releases it (so does the death of the process).
#[derive(Debug)]
pub struct OutLock {
    _dir: File,
}

/// Creates `out` when missing and locks it exclusively (`flock` on the directory itself, so no
/// file is added to it), before the run writes anything there: a second run into the same
/// folder is refused, naming the process that holds it (pid, command, start time).
pub fn lock(out: &Path) -> anyhow::Result<OutLock> {
    if !out.exists() {
        std::fs::create_dir_all(out)
            .with_context(|| format!("creating output directory {}", out.display()))?;
    }
    anyhow::ensure!(
        out.is_dir(),
        "output directory {} is not a directory",
        out.display()
    );
    let dir =
        File::open(out).with_context(|| format!("opening output directory {}", out.display()))?;
    match dir.try_lock() {
        Ok(()) => Ok(OutLock { _dir: dir }),
        Err(TryLockError::WouldBlock) => anyhow::bail!(
            "output directory {} is in use by another run ({}); one run per output folder: wait for it to end or choose another --out",
            out.display(),
            holder(&dir)
        ),
        Err(TryLockError::Error(e)) => {
            Err(e).with_context(|| format!("locking output directory {}", out.display()))
        }
    }
}

/// Who holds the `flock` of `dir`: pid, command line and start time from `/proc/locks` and
/// `/proc/PID` (Linux); "holder unknown" elsewhere.
fn holder(dir: &File) -> String {
    use std::os::unix::fs::MetadataExt;
    let Ok(inode) = dir.metadata().map(|m| m.ino()) else {
        return "holder unknown".into();
    };
    let locks = std::fs::read_to_string("/proc/locks").unwrap_or_default();
    // `1: FLOCK  ADVISORY  WRITE 4242 fd:01:1234567 0 EOF`
    let pid = locks.lines().find_map(|line| {
        let fields: Vec<&str> = line.split_whitespace().collect();
        let (kind, pid, id) = (fields.get(1)?, fields.get(4)?, fields.get(5)?);
        let ino = id.rsplit(':').next()?.parse::<u64>().ok()?;
        (*kind == "FLOCK" && ino == inode).then(|| pid.parse::<u32>().ok())?
    });
    let Some(pid) = pid else {
        return "holder unknown".into();
    };
    let command = std::fs::read(format!("/proc/{pid}/cmdline"))
        .map(|b| {
            let words: Vec<String> = b
                .split(|&c| c == 0)
                .filter(|w| !w.is_empty())
                .map(|w| String::from_utf8_lossy(w).into_owned())
                .collect();
            words.join(" ")
        })
        .unwrap_or_default();
    let started = std::fs::metadata(format!("/proc/{pid}"))
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or_else(|| "unknown".to_string(), |d| utc(d.as_secs()));
    format!("pid {pid}, started {started}: {command}")
}

/// `YYYY-MM-DD HH:MM:SS UTC` of a UNIX time (civil from days, Howard Hinnant's algorithm).
fn utc(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02} UTC",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// Makes `out` ready for a run: creates it when missing; an empty folder is used as it is. A
/// folder with entries is refused unless `overwrite`; with `overwrite` every entry must be one
/// that a run writes ([`is_run_output`]), and those are removed. `keep` (the record a restart
/// reads) must not be among them.
pub fn prepare(out: &Path, overwrite: bool, keep: Option<&Path>) -> anyhow::Result<()> {
    if !out.exists() {
        return std::fs::create_dir_all(out)
            .with_context(|| format!("creating output directory {}", out.display()));
    }
    anyhow::ensure!(
        out.is_dir(),
        "output directory {} is not a directory",
        out.display()
    );
    let mut names = Vec::new();
    for entry in std::fs::read_dir(out)
        .with_context(|| format!("listing output directory {}", out.display()))?
    {
        let entry = entry.with_context(|| format!("listing output directory {}", out.display()))?;
        let is_dir = entry.file_type().map(|t| t.is_dir()).unwrap_or(false);
        names.push((entry.file_name().to_string_lossy().into_owned(), is_dir));
    }
    if names.is_empty() {
        return Ok(());
    }
    names.sort();
    let listed = |names: &[&(String, bool)]| {
        let shown: Vec<&str> = names.iter().take(5).map(|(n, _)| n.as_str()).collect();
        let more = names.len().saturating_sub(shown.len());
        if more > 0 {
            format!("{} and {more} more", shown.join(", "))
        } else {
            shown.join(", ")
        }
    };
    let all: Vec<&(String, bool)> = names.iter().collect();
    anyhow::ensure!(
        overwrite,
        "output directory {} is not empty ({} entries: {}); pass --overwrite to replace the files of the earlier run there, or choose another --out",
        out.display(),
        names.len(),
        listed(&all)
    );
    let foreign: Vec<&(String, bool)> = names
        .iter()
        .filter(|(name, is_dir)| !is_run_output(name, *is_dir))
        .collect();
    anyhow::ensure!(
        foreign.is_empty(),
        "output directory {} holds entries no run writes ({}); --overwrite removes only a run's files: move them or choose another --out",
        out.display(),
        listed(&foreign)
    );
    if let Some(keep) = keep
        && let (Ok(keep), Ok(dir)) = (keep.canonicalize(), out.canonicalize())
        && keep.parent() == Some(dir.as_path())
    {
        anyhow::bail!(
            "the record to restart from, {}, lies in the output directory {} that --overwrite would clear; choose another --out",
            keep.display(),
            out.display()
        );
    }
    for (name, is_dir) in &names {
        let path = out.join(name);
        let removed = if *is_dir {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
        removed.with_context(|| format!("removing {} of an earlier run", path.display()))?;
    }
    Ok(())
}

/// Whether `name` in an output folder is something a run (or `report figures` with its default
/// folder, or `inspect --recover`) writes: `exchange.mcap` and other `.mcap` records,
/// `summary.json`, `scene.toml`, `outputs.csv`, `ledger.csv`, `links_broken.csv`,
/// `probe_<name>.csv`, `<kind>_<k>.<csv|vtk|vti|vtp>` for the kinds `fluid`, `surface`, `loads`,
/// `solid`, `particles`, `wet`, the `.pvd` series (and their `.pvd.tmp`), and the folder
/// `report` (and `figures`, its name before).
pub fn is_run_output(name: &str, is_dir: bool) -> bool {
    if is_dir {
        return name == "report" || name == "figures";
    }
    const FIXED: [&str; 6] = [
        "exchange.mcap",
        "summary.json",
        "scene.toml",
        "outputs.csv",
        "ledger.csv",
        "links_broken.csv",
    ];
    const KINDS: [&str; 6] = ["fluid", "surface", "loads", "solid", "particles", "wet"];
    if FIXED.contains(&name)
        || name.ends_with(".mcap")
        || name.ends_with(".pvd")
        || name.ends_with(".pvd.tmp")
        || (name.starts_with("probe_") && name.ends_with(".csv"))
    {
        return true;
    }
    let Some((stem, ext)) = name.rsplit_once('.') else {
        return false;
    };
    let Some((kind, k)) = stem.rsplit_once('_') else {
        return false;
    };
    ["csv", "vtk", "vti", "vtp"].contains(&ext)
        && KINDS.contains(&kind)
        && !k.is_empty()
        && k.bytes().all(|b| b.is_ascii_digit())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_dates() {
        assert_eq!(utc(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(utc(951_782_400), "2000-02-29 00:00:00 UTC");
        assert_eq!(utc(1_796_515_199), "2026-12-05 23:59:59 UTC");
    }

    #[test]
    fn a_second_lock_of_a_folder_is_refused_naming_the_holder() {
        let dir = std::env::temp_dir().join(format!("cosim-lock-{}", std::process::id()));
        let first = lock(&dir).expect("first lock");
        let err = lock(&dir).expect_err("second lock").to_string();
        assert!(err.contains("in use by another run"), "{err}");
        assert!(
            err.contains(&format!("pid {}", std::process::id())),
            "{err}"
        );
        drop(first);
        let again = lock(&dir).expect("lock after release");
        drop(again);
        std::fs::remove_dir_all(&dir).expect("clean up");
    }

    #[test]
    fn run_outputs_are_told_from_other_files() {
        for name in [
            "exchange.mcap",
            "exchange.recovered.mcap",
            "summary.json",
            "scene.toml",
            "outputs.csv",
            "ledger.csv",
            "probe_tip.csv",
            "fluid_0.csv",
            "fluid_12.vti",
            "fluid_3.vtk",
            "surface_2.csv",
            "loads_2.csv",
            "solid_1.vtp",
            "particles_1.vtp",
            "wet_7.vtk",
            "fluid.pvd",
            "wet.pvd.tmp",
        ] {
            assert!(is_run_output(name, false), "{name}");
        }
        for name in [
            "notes.txt",
            "fluid_.csv",
            "fluid_a.vti",
            "mesh_1.vtp",
            "fluid_1.png",
            "scene.toml.bak",
            "sod.toml",
            "figures",
        ] {
            assert!(!is_run_output(name, false), "{name}");
        }
        assert!(is_run_output("figures", true));
        assert!(is_run_output("report", true));
        assert!(!is_run_output("data", true));
    }
}
