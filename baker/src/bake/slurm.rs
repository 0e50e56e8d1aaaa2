//! Slurm job scripts for one bake split into shards: an array job of `baker bake --shard I/N`
//! tasks, a merge job that waits for all of them (`afterok`), and a script that submits both.
//! `baker slurm` (the CLI) turns its flags into a [`SlurmRequest`] and writes what
//! [`JobScripts`] makes.

use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::error::UsageError;

/// What `baker slurm` was asked for, before paths are resolved.
#[derive(Debug, Clone)]
pub struct SlurmRequest {
    /// Spec paths as given.
    pub specs: Vec<PathBuf>,
    pub shards: u32,
    pub partition: Option<String>,
    /// A Slurm time limit, checked by [`parse_time`].
    pub time: Option<String>,
    pub account: Option<String>,
    /// A Slurm memory size, checked by [`parse_mem`].
    pub mem: Option<String>,
    /// Output root of the merge.
    pub out: PathBuf,
    /// Directory for scripts, logs and shards (default: `slurm/<first spec name>`).
    pub work: Option<PathBuf>,
    pub threads: u32,
    pub job_name: Option<String>,
    /// Extra `baker bake` arguments for every shard.
    pub bake_args: Vec<String>,
}

/// Runs `sbatch ARGS` (`program` is `sbatch`), returns the job id it prints (`--parsable`:
/// `id[;cluster]`).
pub fn sbatch(program: &str, args: &[String]) -> anyhow::Result<String> {
    let out = Command::new(program).args(args).output().map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            anyhow::anyhow!(
                "{program} is not on PATH: run this where Slurm's client commands are installed \
                 (Debian: slurm-client), or run the written submit.sh there"
            )
        } else {
            anyhow::Error::new(e).context("running sbatch")
        }
    })?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        anyhow::bail!(
            "{program} {} failed ({}): {}",
            args.join(" "),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    let id = stdout.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        anyhow::bail!("sbatch printed {:?}, not a job id", stdout.trim());
    }
    Ok(id)
}

/// Everything the job scripts are made of, paths resolved.
#[derive(Debug, Clone)]
pub struct JobScripts {
    /// Absolute path of the `baker` binary the jobs run.
    baker: String,
    /// Spec paths exactly as given (relative ones resolve against `cwd`).
    specs: Vec<String>,
    /// Where the jobs run (`--chdir`): the directory `baker slurm` ran in.
    cwd: String,
    /// Absolute `--work`.
    pub work: PathBuf,
    /// Absolute `--out`.
    pub out: PathBuf,
    pub shards: u32,
    threads: u32,
    job_name: String,
    partition: Option<String>,
    time: Option<String>,
    account: Option<String>,
    mem: Option<String>,
    bake_args: Vec<String>,
}

impl JobScripts {
    pub fn new(a: &SlurmRequest, cwd: &Path, baker: &Path) -> anyhow::Result<JobScripts> {
        let stem = a.specs[0]
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "spec".into());
        let work = cwd.join(
            a.work
                .clone()
                .unwrap_or_else(|| Path::new("slurm").join(&stem)),
        );
        let plan = JobScripts {
            baker: text("--baker", baker)?.into(),
            specs: a
                .specs
                .iter()
                .map(|p| text("spec path", p).map(String::from))
                .collect::<anyhow::Result<_>>()?,
            cwd: text("current directory", cwd)?.into(),
            work: work.clone(),
            out: cwd.join(&a.out),
            shards: a.shards,
            threads: a.threads,
            job_name: a.job_name.clone().unwrap_or_else(|| {
                format!("baker-{}", stem.replace(|c: char| c.is_whitespace(), "_"))
            }),
            partition: a.partition.clone(),
            time: a.time.clone(),
            account: a.account.clone(),
            mem: a.mem.clone(),
            bake_args: a.bake_args.clone(),
        };
        text("--work", &plan.work)?;
        text("--out", &plan.out)?;
        if plan.job_name.is_empty() || plan.job_name.chars().any(char::is_control) {
            return Err(UsageError(format!(
                "--job-name {:?}: must be non-empty, without control characters",
                plan.job_name
            ))
            .into());
        }
        for (what, v) in [
            ("--partition", plan.partition.as_ref()),
            ("--account", plan.account.as_ref()),
        ] {
            if let Some(v) = v {
                if v.is_empty() || v.starts_with('-') || v.chars().any(char::is_whitespace) {
                    return Err(UsageError(format!(
                        "{what} {v:?}: must be a non-empty name without spaces"
                    ))
                    .into());
                }
            }
        }
        for arg in &plan.bake_args {
            if arg.chars().any(char::is_control) {
                return Err(UsageError(format!(
                    "extra bake argument {arg:?}: contains a control character"
                ))
                .into());
            }
        }
        Ok(plan)
    }

    pub fn work_path(&self, name: &str) -> String {
        self.work.join(name).to_string_lossy().into_owned()
    }

    /// `WORK/logs/NAME` for `--output`, where `%` starts a pattern (`%a`: the array index): a
    /// literal `%` in the path is written `%%`.
    fn log_pattern(&self, name: &str) -> String {
        format!("{}/{name}", self.work_path("logs").replace('%', "%%"))
    }

    /// `#SBATCH` lines shared by both jobs. sbatch reads them with shell-like quoting, so the
    /// same [`shell_quote`] applies.
    fn common_directives(&self, job_name: &str, log: &str) -> String {
        let mut s = String::new();
        let mut d =
            |opt: &str, v: &str| s.push_str(&format!("#SBATCH --{opt}={}\n", shell_quote(v)));
        d("job-name", job_name);
        d("output", log);
        d("chdir", &self.cwd);
        d("cpus-per-task", &self.threads.to_string());
        for (opt, v) in [
            ("partition", &self.partition),
            ("time", &self.time),
            ("account", &self.account),
            ("mem", &self.mem),
        ] {
            if let Some(v) = v {
                d(opt, v);
            }
        }
        s
    }

    /// The array job: task I of N bakes shard I into WORK/shard-I.
    pub fn bake_script(&self) -> String {
        let n = self.shards;
        let mut s = String::from("#!/bin/bash\n");
        s.push_str(&format!(
            "# Generated by `baker slurm`: shard $SLURM_ARRAY_TASK_ID of {n} of a bake; \
             merge.sbatch assembles them.\n"
        ));
        s.push_str(&self.common_directives(&self.job_name, &self.log_pattern("shard-%a.log")));
        s.push_str(&format!("#SBATCH --array=1-{n}\n"));
        s.push_str("set -euo pipefail\n");
        s.push_str(": \"${SLURM_ARRAY_TASK_ID:?run this with sbatch, as an array job}\"\n");
        s.push_str(&format!("exec {} bake", shell_quote(&self.baker)));
        for spec in &self.specs {
            s.push_str(&format!(" \\\n  {}", shell_quote(spec)));
        }
        if !self.bake_args.is_empty() {
            let args: Vec<_> = self.bake_args.iter().map(|a| shell_quote(a)).collect();
            s.push_str(&format!(" \\\n  {}", args.join(" ")));
        }
        s.push_str(&format!(
            " \\\n  --shard \"$SLURM_ARRAY_TASK_ID\"/{n} \\\n  --out {}\"$SLURM_ARRAY_TASK_ID\" \\\n  \
             --threads \"${{SLURM_CPUS_PER_TASK:-{}}}\" \\\n  --progress json\n",
            shell_quote(&self.work_path("shard-")),
            self.threads
        ));
        s
    }

    /// The merge job: every shard directory, listed explicitly (stale ones from an earlier
    /// run with more shards are not picked up).
    pub fn merge_script(&self) -> String {
        let mut s = String::from("#!/bin/bash\n");
        s.push_str(&format!(
            "# Generated by `baker slurm`: assembles the {} shards of bake.sbatch into the final \
             tables.\n",
            self.shards
        ));
        s.push_str(&self.common_directives(
            &format!("{}-merge", self.job_name),
            &self.log_pattern("merge.log"),
        ));
        // A failed shard makes the afterok dependency unsatisfiable: cancel, don't wait forever.
        s.push_str("#SBATCH --kill-on-invalid-dep=yes\n");
        s.push_str("set -euo pipefail\n");
        s.push_str(&format!("exec {} merge", shell_quote(&self.baker)));
        for i in 1..=self.shards {
            s.push_str(&format!(
                " \\\n  {}",
                shell_quote(&self.work_path(&format!("shard-{i}")))
            ));
        }
        s.push_str(&format!(
            " \\\n  -o {} \\\n  --threads \"${{SLURM_CPUS_PER_TASK:-{}}}\" \\\n  --progress json\n",
            shell_quote(&self.out.to_string_lossy()),
            self.threads
        ));
        s
    }

    pub fn sbatch_array_args(&self) -> Vec<String> {
        vec!["--parsable".into(), self.work_path("bake.sbatch")]
    }

    pub fn sbatch_merge_args(&self, array_job: &str) -> Vec<String> {
        vec![
            "--parsable".into(),
            format!("--dependency=afterok:{array_job}"),
            self.work_path("merge.sbatch"),
        ]
    }

    /// What `--submit` does, as a script to run by hand (e.g. on a login node).
    pub fn submit_script(&self) -> String {
        let q = |args: &[String]| {
            args.iter()
                .map(|a| shell_quote(a))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let mut s = String::from("#!/bin/bash\n");
        s.push_str(
            "# Generated by `baker slurm`: submits the shard array, then the merge, which starts \
             once every shard has exited 0.\n",
        );
        s.push_str("set -euo pipefail\n");
        // --parsable prints `id` or `id;cluster`.
        s.push_str(&format!(
            "array=$(sbatch {})\narray=${{array%%;*}}\n",
            q(&self.sbatch_array_args())
        ));
        s.push_str("echo \"bake array job $array\"\n");
        s.push_str(&format!(
            "merge=$(sbatch --parsable --dependency=afterok:\"$array\" {})\nmerge=${{merge%%;*}}\n",
            shell_quote(&self.work_path("merge.sbatch"))
        ));
        s.push_str("echo \"merge job $merge\"\n");
        s
    }
}

/// `path` as UTF-8 without control characters (it goes into shell and `#SBATCH` lines).
fn text<'a>(what: &str, path: &'a Path) -> anyhow::Result<&'a str> {
    match path.to_str() {
        Some(s) if !s.chars().any(char::is_control) => Ok(s),
        _ => Err(UsageError(format!(
            "{what} {}: must be UTF-8 without control characters to go into a job script",
            path.display()
        ))
        .into()),
    }
}

/// `s` as one shell word: as is when it has only safe characters, else single-quoted.
pub fn shell_quote(s: &str) -> Cow<'_, str> {
    let safe = |c: char| c.is_ascii_alphanumeric() || "_-+=/.,:@%".contains(c);
    if !s.is_empty() && s.chars().all(safe) {
        Cow::Borrowed(s)
    } else {
        Cow::Owned(format!("'{}'", s.replace('\'', r"'\''")))
    }
}

/// A Slurm time limit (`sbatch --time`): `M`, `M:S`, `H:M:S`, `D-H`, `D-H:M`, `D-H:M:S`,
/// `INFINITE` or `UNLIMITED`. Seconds and minutes below a larger unit must be < 60, hours
/// after days < 24.
pub fn parse_time(s: &str) -> Result<String, String> {
    if s.eq_ignore_ascii_case("infinite") || s.eq_ignore_ascii_case("unlimited") {
        return Ok(s.to_string());
    }
    let bad = |why: &str| {
        Err(format!(
            "{s:?} is not a Slurm time limit ({why}); allowed: M, M:S, H:M:S, D-H, D-H:M, \
             D-H:M:S, UNLIMITED (e.g. 90, 1:30:00, 2-12)"
        ))
    };
    let num = |p: &str| {
        if !p.is_empty() && p.len() <= 9 && p.bytes().all(|b| b.is_ascii_digit()) {
            p.parse::<u32>().ok()
        } else {
            None
        }
    };
    let (days, rest) = match s.split_once('-') {
        Some((d, r)) => (Some(d), r),
        None => (None, s),
    };
    let parts: Vec<&str> = rest.split(':').collect();
    let Some(values) = parts.iter().map(|p| num(p)).collect::<Option<Vec<u32>>>() else {
        return bad("every field must be a number");
    };
    if let Some(d) = days {
        if num(d).is_none() {
            return bad("days must be a number");
        }
        // D-H, D-H:M, D-H:M:S
        if values.len() > 3 {
            return bad("too many fields");
        }
        if values[0] >= 24 {
            return bad("hours after days must be < 24");
        }
        if values[1..].iter().any(|&v| v >= 60) {
            return bad("minutes and seconds must be < 60");
        }
    } else {
        match values.len() {
            1 => {}                                     // M
            2 if values[1] < 60 => {}                   // M:S
            3 if values[1] < 60 && values[2] < 60 => {} // H:M:S
            2 | 3 => return bad("minutes and seconds must be < 60"),
            _ => return bad("too many fields"),
        }
    }
    Ok(s.to_string())
}

/// A Slurm memory size (`sbatch --mem`): a positive integer with an optional K, M, G or T
/// suffix (default M).
pub fn parse_mem(s: &str) -> Result<String, String> {
    let digits = s
        .strip_suffix(['K', 'M', 'G', 'T', 'k', 'm', 'g', 't'])
        .unwrap_or(s);
    match digits.parse::<u64>() {
        Ok(v) if v > 0 && digits.bytes().all(|b| b.is_ascii_digit()) => Ok(s.to_string()),
        _ => Err(format!(
            "{s:?} is not a Slurm memory size; allowed: a positive integer with an optional \
             K, M, G or T suffix (e.g. 4G, 500M)"
        )),
    }
}
