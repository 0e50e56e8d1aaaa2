//! `baker export TABLE --to FORMAT [--entry NAME] [-o FILE]`.

use std::path::PathBuf;

use clap::Args;

use super::UsageError;

use crate::export::ExportRequest;

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A baked table: `out/<spec>/profiles.bkt` (skin) or `out/fibers/<entry>/*.bcsdf` (fiber).
    pub table: PathBuf,
    /// Target. Skin: burley, mtlx (OpenPBR/MaterialX), blender, unreal, unity, pbrt, mitsuba.
    /// Fiber: chiang, pbrt, mitsuba, blender.
    #[arg(long = "to")]
    pub to: String,
    /// Skin entry (default: all, where the target takes several) or fiber variant (default:
    /// the first).
    #[arg(long)]
    pub entry: Option<String>,
    /// Output file (default: stdout).
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
}

pub fn run(a: ExportArgs) -> anyhow::Result<()> {
    let req = ExportRequest {
        table: a.table,
        to: a.to,
        entry: a.entry,
        output: a.output,
    };
    let mut head = [0u8; 8];
    {
        use std::io::Read as _;
        // A table is a regular file: a directory or device is named as such, not opened.
        match std::fs::metadata(&req.table) {
            Ok(m) if m.is_file() => {}
            Ok(m) => {
                return Err(UsageError(format!(
                    "{}: is {}; expected a baked table (profiles.bkt or a .bcsdf file)",
                    req.table.display(),
                    crate::files::special_kind(&m.file_type()).unwrap_or("not a regular file")
                ))
                .into())
            }
            Err(e) => {
                return Err(UsageError(format!("{}: {e}", req.table.display())).into());
            }
        }
        let mut f = std::fs::File::open(&req.table)
            .map_err(|e| anyhow::anyhow!("cannot open {}: {e}", req.table.display()))?;
        let _ = f.read(&mut head)?;
    }
    match &head {
        b"BAKERTBL" => crate::export::skin::run(&req),
        b"BAKERFIB" => crate::export::hair::run(&req),
        _ => Err(UsageError(format!(
            "{}: not a baker table (expected profiles.bkt or a .bcsdf file)",
            req.table.display()
        ))
        .into()),
    }
}
