//! The output folder of `coupler-node run`: created when missing, refused when it holds anything
//! unless `--overwrite`, which clears the files an earlier run wrote (and only those), so that no
//! stale output (a `fluid_3.vti` of a run with more outputs) is left beside the new ones.

use std::path::Path;

use anyhow::Context;

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
/// `figures`.
pub fn is_run_output(name: &str, is_dir: bool) -> bool {
    if is_dir {
        return name == "figures";
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
        assert!(!is_run_output("data", true));
    }
}
