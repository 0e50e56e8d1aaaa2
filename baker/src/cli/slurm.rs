//! `baker slurm`: one bake split over a Slurm cluster.
//!
//! Writes, into `--work DIR`:
//! - `bake.sbatch`: an array job (`--array=1-N`); task I runs `baker bake SPEC… --shard I/N
//!   --out DIR/shard-I`, one deterministic slice of the work units;
//! - `merge.sbatch`: `baker merge DIR/shard-1 … DIR/shard-N -o OUT`, which assembles the same
//!   tables, byte for byte, as `baker bake SPEC… --out OUT` on one machine;
//! - `submit.sh`: submits the array, then the merge with `--dependency=afterok:<array>` (it
//!   starts only once every shard has exited 0);
//! - `logs/`: one log per shard (`shard-<I>.log`) and `merge.log`.
//!
//! `--submit` does what `submit.sh` does and prints the two job ids. The jobs run in the
//! directory `baker slurm` ran in (`--chdir`), and the spec paths are passed as given: the spec
//! path is recorded in the tables and manifests, so this is what keeps the merged output
//! identical to a local bake from the same directory. Every other path is made absolute. The
//! compute nodes must see this directory, the specs, `--work`, `--out` and the `baker` binary at
//! the same paths (a shared file system).

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use crate::bake::slurm::{parse_mem, parse_time, sbatch, shell_quote, JobScripts, SlurmRequest};
use crate::error::UsageError;
use crate::output::atomic;

#[derive(Debug, Args)]
pub struct SlurmArgs {
    /// Spec files (YAML), baked together as by `baker bake`.
    #[arg(required = true)]
    pub specs: Vec<PathBuf>,
    /// Number of shards: the array job's tasks (`--array=1-N`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub shards: u32,
    /// Slurm partition (`sbatch --partition`); default: the cluster's default partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit per job, in Slurm's format: `M`, `M:S`, `H:M:S`, `D-H`, `D-H:M`, `D-H:M:S`
    /// or `UNLIMITED`.
    #[arg(long, value_parser = parse_time)]
    pub time: Option<String>,
    /// Account charged for the jobs (`sbatch --account`).
    #[arg(long)]
    pub account: Option<String>,
    /// Memory per node (`sbatch --mem`), e.g. `4G`; default: the cluster's default.
    #[arg(long, value_parser = parse_mem)]
    pub mem: Option<String>,
    /// Output root of the merge; each spec ends up in OUT/<spec name>/, as with `baker bake`.
    #[arg(short = 'o', long, default_value = "out")]
    pub out: PathBuf,
    /// Directory for the job scripts, logs and shard directories [default: slurm/<first spec
    /// name>].
    #[arg(long)]
    pub work: Option<PathBuf>,
    /// CPUs per shard (`--cpus-per-task`), and so the bake's worker threads.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub threads: u32,
    /// Job name of the array; the merge job gets `<name>-merge` [default: baker-<first spec
    /// name>].
    #[arg(long)]
    pub job_name: Option<String>,
    /// The `baker` binary the jobs run [default: this executable].
    #[arg(long)]
    pub baker: Option<PathBuf>,
    /// Submit the jobs with `sbatch` and print their ids (otherwise run `WORK/submit.sh`).
    #[arg(long)]
    pub submit: bool,
    /// Bake only this entry (repeatable), as `baker bake --entry`.
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    /// Print only errors (and, with --submit, the job ids).
    #[arg(short, long)]
    pub quiet: bool,
    /// Extra `baker bake` arguments for every shard, after `--`: `-- --photons 20000`.
    #[arg(last = true, value_name = "BAKE_ARGS")]
    pub bake_args: Vec<String>,
}

/// `baker bake` flags that `baker slurm` sets itself, per shard. (`--cache`: each shard keeps
/// its units in its own directory, where `baker merge` collects them.)
const RESERVED_BAKE_FLAGS: [&str; 6] = [
    "--out",
    "-o",
    "--shard",
    "--threads",
    "--progress",
    "--cache",
];

impl SlurmArgs {
    /// The flags as the library's request.
    fn request(&self) -> SlurmRequest {
        SlurmRequest {
            specs: self.specs.clone(),
            shards: self.shards,
            partition: self.partition.clone(),
            time: self.time.clone(),
            account: self.account.clone(),
            mem: self.mem.clone(),
            out: self.out.clone(),
            work: self.work.clone(),
            threads: self.threads,
            job_name: self.job_name.clone(),
            bake_args: self.bake_args_with_entries(),
        }
    }

    /// The extra bake arguments, with `--entry NAME` for each `--entry` of this command.
    fn bake_args_with_entries(&self) -> Vec<String> {
        let mut args = self.bake_args.clone();
        for e in &self.entries {
            args.extend(["--entry".to_string(), e.clone()]);
        }
        args
    }
}

pub fn run(a: SlurmArgs) -> anyhow::Result<()> {
    // Everything a shard would reject is rejected here, before anything is queued.
    for spec in &a.specs {
        crate::bake::load_checked(spec, &crate::spec::budget::Overrides::none())?;
        crate::bake::spec_stem(spec)?;
    }
    check_bake_args(&a.specs, &a.bake_args_with_entries())?;

    let cwd = std::env::current_dir().context("reading the current directory")?;
    let baker = match &a.baker {
        Some(b) => cwd.join(b),
        None => std::env::current_exe().context("locating the baker executable")?,
    };
    let plan = JobScripts::new(&a.request(), &cwd, &baker)?;

    std::fs::create_dir_all(plan.work.join("logs"))
        .with_context(|| format!("creating {}", plan.work.join("logs").display()))?;
    for (name, text) in [
        ("bake.sbatch", plan.bake_script()),
        ("merge.sbatch", plan.merge_script()),
        ("submit.sh", plan.submit_script()),
    ] {
        let path = plan.work.join(name);
        atomic::write(&path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        if name == "submit.sh" {
            use std::os::unix::fs::PermissionsExt as _;
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755))
                .with_context(|| format!("making {} executable", path.display()))?;
        }
    }
    let work = plan.work.display();
    if !a.quiet {
        outln!(
            "wrote {work}/bake.sbatch ({} shards), {work}/merge.sbatch, {work}/submit.sh",
            plan.shards
        )?;
    }
    if !a.submit {
        if !a.quiet {
            outln!("submit with: {}", shell_quote(&format!("{work}/submit.sh")))?;
        }
        return Ok(());
    }

    let array = sbatch("sbatch", &plan.sbatch_array_args())?;
    outln!("bake array job {array}")?;
    let merge = sbatch("sbatch", &plan.sbatch_merge_args(&array))?;
    outln!("merge job {merge}")?;
    if !a.quiet {
        outln!("logs: {work}/logs/  output: {}/", plan.out.display())?;
    }
    Ok(())
}

/// Parses the extra bake arguments with `baker bake`'s own parser, and rejects the flags set
/// per shard.
fn check_bake_args(specs: &[PathBuf], bake_args: &[String]) -> anyhow::Result<()> {
    for arg in bake_args {
        // `--out=X`, and `-oX` (a short flag with its value attached).
        let flag = match arg.split('=').next().unwrap_or(arg) {
            f if f.starts_with("-o") && !f.starts_with("--") => "-o",
            f => f,
        };
        if RESERVED_BAKE_FLAGS.contains(&flag) {
            return Err(UsageError(format!(
                "extra bake argument {arg:?}: baker slurm sets {} itself (see --work, --out, \
                 --threads)",
                RESERVED_BAKE_FLAGS.join(", ")
            ))
            .into());
        }
    }
    /// `baker bake`'s flags alone, to check the extra arguments as `baker bake` would.
    #[derive(clap::Parser)]
    #[command(name = "baker bake")]
    struct BakeLine {
        #[command(flatten)]
        _bake: super::bake::BakeArgs,
    }
    let argv = ["baker bake"]
        .into_iter()
        .map(Into::into)
        .chain(specs.iter().map(|p| p.clone().into_os_string()))
        .chain(bake_args.iter().map(Into::into));
    <BakeLine as clap::Parser>::try_parse_from(argv).map_err(|e| {
        // clap's first line says what is wrong; the rest is usage for the wrong command line.
        let msg = e.render().to_string();
        let first = msg.lines().next().unwrap_or_default();
        UsageError(format!(
            "extra bake arguments {bake_args:?}: {} (see baker bake --help)",
            first.strip_prefix("error: ").unwrap_or(first)
        ))
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::process::Command;

    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct T {
        #[command(flatten)]
        a: SlurmArgs,
    }

    fn args(argv: &[&str]) -> Result<SlurmArgs, clap::Error> {
        T::try_parse_from(std::iter::once("slurm").chain(argv.iter().copied())).map(|t| t.a)
    }

    fn plan(argv: &[&str], cwd: &str, baker: &str) -> JobScripts {
        JobScripts::new(
            &args(argv).unwrap().request(),
            Path::new(cwd),
            Path::new(baker),
        )
        .unwrap()
    }

    #[test]
    fn array_job_covers_every_shard_and_the_merge_lists_them() {
        let p = plan(
            &[
                "specs/skin.yaml",
                "specs/fibers.yaml",
                "--shards",
                "4",
                "--threads",
                "2",
            ],
            "/home/u/proj",
            "/opt/baker/bin/baker",
        );
        let bake = p.bake_script();
        assert!(bake.starts_with("#!/bin/bash\n"));
        assert!(bake.contains("#SBATCH --array=1-4\n"), "{bake}");
        assert!(bake.contains("#SBATCH --job-name=baker-skin\n"), "{bake}");
        assert!(bake.contains("#SBATCH --cpus-per-task=2\n"), "{bake}");
        assert!(bake.contains("#SBATCH --chdir=/home/u/proj\n"), "{bake}");
        assert!(
            bake.contains("#SBATCH --output=/home/u/proj/slurm/skin/logs/shard-%a.log\n"),
            "{bake}"
        );
        assert!(bake.contains("set -euo pipefail\n"));
        assert!(
            bake.contains(
                "exec /opt/baker/bin/baker bake \\\n  specs/skin.yaml \\\n  specs/fibers.yaml"
            ),
            "{bake}"
        );
        assert!(
            bake.contains("--shard \"$SLURM_ARRAY_TASK_ID\"/4"),
            "{bake}"
        );
        assert!(
            bake.contains("--out /home/u/proj/slurm/skin/shard-\"$SLURM_ARRAY_TASK_ID\""),
            "{bake}"
        );
        assert!(
            bake.contains("--threads \"${SLURM_CPUS_PER_TASK:-2}\""),
            "{bake}"
        );
        assert!(bake.contains("--progress json"), "{bake}");
        assert!(
            !bake.contains("--partition") && !bake.contains("--time"),
            "{bake}"
        );

        let merge = p.merge_script();
        assert!(
            merge.contains("#SBATCH --job-name=baker-skin-merge\n"),
            "{merge}"
        );
        assert!(
            merge.contains("#SBATCH --kill-on-invalid-dep=yes\n"),
            "{merge}"
        );
        assert!(!merge.contains("--array"), "{merge}");
        let shards: Vec<&str> = merge
            .split_whitespace()
            .filter(|w| w.contains("/shard-"))
            .collect();
        assert_eq!(
            shards,
            (1..=4)
                .map(|i| format!("/home/u/proj/slurm/skin/shard-{i}"))
                .collect::<Vec<_>>()
        );
        assert!(merge.contains("  -o /home/u/proj/out \\\n"), "{merge}");
        assert!(
            merge.contains("--threads \"${SLURM_CPUS_PER_TASK:-2}\""),
            "{merge}"
        );
    }

    #[test]
    fn merge_waits_for_the_whole_array() {
        let p = plan(&["a.yaml", "--shards", "3"], "/w", "/b/baker");
        assert_eq!(
            p.sbatch_merge_args("1234"),
            [
                "--parsable",
                "--dependency=afterok:1234",
                "/w/slurm/a/merge.sbatch"
            ]
        );
        assert_eq!(
            p.sbatch_array_args(),
            ["--parsable", "/w/slurm/a/bake.sbatch"]
        );
        let submit = p.submit_script();
        assert!(
            submit.contains("array=$(sbatch --parsable /w/slurm/a/bake.sbatch)\n"),
            "{submit}"
        );
        assert!(
            submit.contains(
                "merge=$(sbatch --parsable --dependency=afterok:\"$array\" /w/slurm/a/merge.sbatch)\n"
            ),
            "{submit}"
        );
        assert!(submit.contains("array=${array%%;*}"), "{submit}");
    }

    #[test]
    fn scheduler_options_become_directives() {
        let p = plan(
            &[
                "a.yaml",
                "--shards",
                "2",
                "--partition",
                "gpu,cpu",
                "--time",
                "1-02:30",
                "--account",
                "proj42",
                "--mem",
                "8G",
                "--job-name",
                "skin",
                "--work",
                "jobs",
                "--out",
                "/data/out",
            ],
            "/w",
            "/b/baker",
        );
        for s in [p.bake_script(), p.merge_script()] {
            for line in [
                "#SBATCH --partition=gpu,cpu\n",
                "#SBATCH --time=1-02:30\n",
                "#SBATCH --account=proj42\n",
                "#SBATCH --mem=8G\n",
            ] {
                assert!(s.contains(line), "{line} missing from\n{s}");
            }
        }
        assert!(p.bake_script().contains("#SBATCH --job-name=skin\n"));
        assert!(p
            .bake_script()
            .contains("--out /w/jobs/shard-\"$SLURM_ARRAY_TASK_ID\""));
        assert!(p.merge_script().contains("#SBATCH --job-name=skin-merge\n"));
        assert!(p.merge_script().contains("-o /data/out \\\n"));
    }

    #[test]
    fn quoting() {
        assert_eq!(shell_quote("/a/b-c_d.yaml"), "/a/b-c_d.yaml");
        assert_eq!(shell_quote("/my dir/x"), "'/my dir/x'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
        assert_eq!(shell_quote("$HOME"), "'$HOME'");
        assert_eq!(shell_quote(""), "''");

        let p = plan(
            &[
                "my specs/skin.yaml",
                "--shards",
                "2",
                "--",
                "--entry",
                "type I $x",
            ],
            "/home/u/it's here",
            "/opt/b k/baker",
        );
        let bake = p.bake_script();
        assert!(
            bake.contains("#SBATCH --chdir='/home/u/it'\\''s here'\n"),
            "{bake}"
        );
        assert!(
            bake.contains(
                "#SBATCH --output='/home/u/it'\\''s here/slurm/skin/logs/shard-%a.log'\n"
            ),
            "{bake}"
        );
        assert!(bake.contains("exec '/opt/b k/baker' bake"), "{bake}");
        assert!(bake.contains("'my specs/skin.yaml'"), "{bake}");
        assert!(bake.contains("\n  --entry 'type I $x' \\\n"), "{bake}");
        assert!(
            bake.contains(
                "--out '/home/u/it'\\''s here/slurm/skin/shard-'\"$SLURM_ARRAY_TASK_ID\""
            ),
            "{bake}"
        );
    }

    /// The generated scripts run under bash and hand `baker` exactly the intended arguments,
    /// whatever the paths contain.
    #[test]
    fn scripts_pass_exact_arguments_through_bash() {
        let Ok(status) = Command::new("bash").arg("--version").output() else {
            eprintln!("no bash: skipped");
            return;
        };
        assert!(status.status.success());
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("it's a \"dir\" $HOME");
        std::fs::create_dir_all(&root).unwrap();
        let fake = root.join("fake baker");
        std::fs::write(
            &fake,
            "#!/bin/sh\nfor a in \"$@\"; do printf '%s\\n' \"$a\"; done\n",
        )
        .unwrap();
        use std::os::unix::fs::PermissionsExt as _;
        std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
        let root_s = root.to_str().unwrap();
        let p = plan(
            &[
                "a b.yaml",
                "--shards",
                "3",
                "--",
                "--photons",
                "2000",
                "--entry",
                "x'y z",
            ],
            root_s,
            fake.to_str().unwrap(),
        );
        let run = |script: String, env: &[(&str, &str)]| {
            let out = Command::new("bash")
                .arg("-c")
                .arg(script)
                .env_remove("SLURM_CPUS_PER_TASK")
                .envs(env.iter().copied())
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            String::from_utf8(out.stdout)
                .unwrap()
                .lines()
                .map(String::from)
                .collect::<Vec<_>>()
        };
        let got = run(p.bake_script(), &[("SLURM_ARRAY_TASK_ID", "2")]);
        let shard2 = format!("{root_s}/slurm/a b/shard-2");
        assert_eq!(
            got,
            [
                "bake",
                "a b.yaml",
                "--photons",
                "2000",
                "--entry",
                "x'y z",
                "--shard",
                "2/3",
                "--out",
                &shard2,
                "--threads",
                "1",
                "--progress",
                "json",
            ]
        );
        let got = run(
            p.bake_script(),
            &[("SLURM_ARRAY_TASK_ID", "3"), ("SLURM_CPUS_PER_TASK", "8")],
        );
        assert_eq!(got[got.len() - 3], "8");
        // Outside Slurm the array job refuses to run.
        let out = Command::new("bash")
            .arg("-c")
            .arg(p.bake_script())
            .env_remove("SLURM_ARRAY_TASK_ID")
            .output()
            .unwrap();
        assert!(!out.status.success());
        assert!(String::from_utf8_lossy(&out.stderr).contains("run this with sbatch"));

        let got = run(p.merge_script(), &[]);
        let mut want = vec!["merge".to_string()];
        want.extend((1..=3).map(|i| format!("{root_s}/slurm/a b/shard-{i}")));
        want.extend(["-o".to_string(), format!("{root_s}/out")]);
        want.extend(["--threads", "1", "--progress", "json"].map(String::from));
        assert_eq!(got, want);

        // submit.sh against a fake sbatch that logs its arguments and answers `id;cluster`.
        let bin = root.join("bin");
        std::fs::create_dir_all(&bin).unwrap();
        let log = root.join("sbatch.log");
        std::fs::write(
            bin.join("sbatch"),
            format!(
                "#!/bin/sh\nprintf '%s|' \"$@\" >> {}\necho >> {}\nn=$(wc -l < {} | tr -d ' ')\necho \"$((100 + n));cluster\"\n",
                shell_quote(log.to_str().unwrap()),
                shell_quote(log.to_str().unwrap()),
                shell_quote(log.to_str().unwrap()),
            ),
        )
        .unwrap();
        std::fs::set_permissions(bin.join("sbatch"), std::fs::Permissions::from_mode(0o755))
            .unwrap();
        let path = format!(
            "{}:{}",
            bin.display(),
            std::env::var("PATH").unwrap_or_default()
        );
        let got = run(p.submit_script(), &[("PATH", &path)]);
        assert_eq!(got, ["bake array job 101", "merge job 102"]);
        let calls = std::fs::read_to_string(&log).unwrap();
        assert_eq!(
            calls.lines().collect::<Vec<_>>(),
            [
                format!("--parsable|{root_s}/slurm/a b/bake.sbatch|"),
                format!("--parsable|--dependency=afterok:101|{root_s}/slurm/a b/merge.sbatch|"),
            ]
        );
    }

    #[test]
    fn time_limits() {
        for ok in [
            "30",
            "90",
            "0:30",
            "120:00",
            "1:30:00",
            "48:00:00",
            "2-12",
            "2-12:30",
            "2-12:30:15",
            "0-0:0:1",
            "UNLIMITED",
            "infinite",
        ] {
            assert_eq!(parse_time(ok).as_deref(), Ok(ok), "{ok}");
        }
        for bad in [
            "",
            "1h",
            "1:60",
            "1:30:60",
            "1:60:00",
            "2-24",
            "2-12:60",
            "2--1",
            "-1",
            "1-",
            "1:2:3:4",
            "2-1:2:3:4",
            "1.5",
            " 30",
            "a-1",
            "1:-1",
        ] {
            assert!(parse_time(bad).is_err(), "{bad} accepted");
        }
        assert!(args(&["a.yaml", "--shards", "2", "--time", "1:61"])
            .unwrap_err()
            .to_string()
            .contains("not a Slurm time limit"));
    }

    #[test]
    fn memory_and_counts() {
        for ok in ["4G", "500M", "1024", "2t"] {
            assert_eq!(parse_mem(ok).as_deref(), Ok(ok));
        }
        for bad in ["", "0", "G", "4GB", "-1G", "1.5G", "+4G"] {
            assert!(parse_mem(bad).is_err(), "{bad} accepted");
        }
        assert!(args(&["a.yaml", "--shards", "0"]).is_err());
        assert!(args(&["a.yaml", "--shards", "2", "--threads", "0"]).is_err());
        assert!(args(&["a.yaml"]).is_err(), "--shards is required");
        assert!(args(&["--shards", "2"]).is_err(), "a spec is required");
        let a = args(&["a.yaml", "b.yaml", "--shards", "2", "--", "--photons", "10"]).unwrap();
        assert_eq!(a.specs, [PathBuf::from("a.yaml"), PathBuf::from("b.yaml")]);
        assert_eq!(a.bake_args, ["--photons", "10"]);
    }

    #[test]
    fn reserved_and_invalid_bake_args_are_rejected() {
        let specs = [PathBuf::from("a.yaml")];
        for reserved in [
            "--out",
            "--out=x",
            "--shard",
            "--threads",
            "--progress=bar",
            "--cache",
            "-o",
            "-ox",
        ] {
            let e = check_bake_args(&specs, &[reserved.into(), "1".into()]).unwrap_err();
            assert!(e.to_string().contains("sets --out, -o, --shard"), "{e}");
        }
        assert!(check_bake_args(&specs, &["--photons".into(), "100".into()]).is_ok());
        let e = check_bake_args(&specs, &["--no-such-flag".into()]).unwrap_err();
        assert!(e.to_string().contains("--no-such-flag"), "{e}");
    }

    #[test]
    fn run_writes_the_scripts() {
        let dir = tempfile::tempdir().unwrap();
        let work = dir.path().join("w");
        let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/specs/profiles_small.yaml");
        let w = work.to_str().unwrap();
        let mut a = args(&[
            spec.to_str().unwrap(),
            "--shards",
            "2",
            "--work",
            w,
            "--baker",
            "/b",
        ])
        .unwrap();
        run(a).unwrap();
        use std::os::unix::fs::PermissionsExt as _;
        let mode = std::fs::metadata(work.join("submit.sh"))
            .unwrap()
            .permissions()
            .mode();
        assert_eq!(mode & 0o111, 0o111, "submit.sh is executable");
        assert!(
            work.join("logs").is_dir(),
            "sbatch does not create --output directories"
        );
        let bake = std::fs::read_to_string(work.join("bake.sbatch")).unwrap();
        assert!(bake.contains("#SBATCH --array=1-2\n") && bake.contains("exec /b bake"));
        assert!(std::fs::read_to_string(work.join("merge.sbatch"))
            .unwrap()
            .contains("shard-2"));

        // A broken spec is reported before anything is written.
        let bad =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/specs/bad/xi_out_of_range.yaml");
        let w2 = dir.path().join("w2");
        a = args(&[
            bad.to_str().unwrap(),
            "--shards",
            "2",
            "--work",
            w2.to_str().unwrap(),
        ])
        .unwrap();
        let e = run(a).unwrap_err();
        assert!(e.downcast_ref::<UsageError>().is_some(), "{e}");
        assert!(!w2.exists());
    }

    #[test]
    fn a_missing_sbatch_is_named() {
        let e = sbatch("baker-test-no-such-sbatch", &["x".into()]).unwrap_err();
        assert!(
            e.to_string()
                .contains("baker-test-no-such-sbatch is not on PATH"),
            "{e}"
        );
        let e = sbatch("false", &[]).unwrap_err();
        assert!(e.to_string().contains("false  failed"), "{e}");
    }

    #[test]
    fn names_with_spaces_and_control_characters_are_rejected() {
        let a = args(&["a.yaml", "--shards", "2", "--partition", "my part"]).unwrap();
        assert!(JobScripts::new(&a.request(), Path::new("/w"), Path::new("/b")).is_err());
        let a = args(&["a\nb.yaml", "--shards", "2"]).unwrap();
        assert!(JobScripts::new(&a.request(), Path::new("/w"), Path::new("/b")).is_err());
    }
}
