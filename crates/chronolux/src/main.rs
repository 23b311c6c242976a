//! `chronolux`: the command line. Arguments and wiring only; no algorithms live here.

mod args;
mod bench;
mod cli;
mod compare;
mod config;
mod denoise;
mod exposure;
mod farm;
mod info;
mod quality;
mod reference;
mod render;
mod scene_input;
mod segment;
mod view;

use clap::Parser;
use std::io::Write;

fn main() {
    if let Err(missing) = cpu_has_build_features() {
        eprintln!(
            "error: this chronolux was built for x86-64-v3 CPUs (AVX2, FMA, BMI, LZCNT: \
             .cargo/config.toml) and this CPU lacks {missing}; build one for any x86-64 CPU \
             with `RUSTFLAGS= cargo build --release` (about 15 % slower)"
        );
        std::process::exit(2);
    }
    run_cli()
}

/// The instruction-set extensions this binary was compiled to use (the `target-cpu` of
/// `.cargo/config.toml`) that the CPU running it lacks: a clear error instead of an
/// illegal-instruction crash on an older machine (a farm node, say). Checked before
/// anything else runs; the rest of the program is in [`run_cli`], which is never inlined
/// here, so no such instruction runs before the check.
fn cpu_has_build_features() -> Result<(), String> {
    #[cfg(target_arch = "x86_64")]
    {
        // (name, compiled to use it, present on this CPU)
        macro_rules! feature {
            ($f:tt) => {
                (
                    $f,
                    cfg!(target_feature = $f),
                    std::is_x86_feature_detected!($f),
                )
            };
        }
        let features = [
            feature!("avx2"),
            feature!("fma"),
            feature!("bmi1"),
            feature!("bmi2"),
            feature!("lzcnt"),
            feature!("popcnt"),
            feature!("movbe"),
            feature!("f16c"),
        ];
        let missing: Vec<&str> = features
            .iter()
            .filter(|(_, built, has)| *built && !*has)
            .map(|(name, _, _)| *name)
            .collect();
        if !missing.is_empty() {
            return Err(missing.join(", "));
        }
    }
    Ok(())
}

#[inline(never)]
fn run_cli() {
    let args = match cli::Cli::try_parse() {
        Ok(a) => a,
        Err(e) if !e.use_stderr() => e.exit(), // --help, --version: stdout, exit 0
        Err(e) => {
            // Usage errors keep the one-line contract of every other error: clap's first
            // paragraph on one line (a missing argument's name is on the lines after
            // "the following required arguments were not provided:").
            let text = e.to_string();
            let first = text
                .lines()
                .map(str::trim)
                .take_while(|l| !l.is_empty())
                .collect::<Vec<_>>()
                .join(" ");
            let first = if first.is_empty() {
                "invalid arguments"
            } else {
                first.strip_prefix("error: ").unwrap_or(&first)
            };
            eprintln!("error: {first} (see --help)");
            std::process::exit(2);
        }
    };
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format(|buf, record| {
            let level = match record.level() {
                log::Level::Error => "error",
                log::Level::Warn => "warning",
                log::Level::Info => "info",
                log::Level::Debug => "debug",
                log::Level::Trace => "trace",
            };
            writeln!(buf, "{level}: {}", record.args())
        })
        .init();
    let result = match args.command {
        // A farm segment (`render --plan P --segment I`) runs the plan's configuration.
        cli::Command::Render(r) if r.plan.is_some() || r.segment.is_some() => {
            farm::render_segment(r)
        }
        cli::Command::Render(r) => render::run(r),
        cli::Command::Info(i) => info::run(i),
        cli::Command::Compare(c) => compare::run(c),
        cli::Command::Reference(r) => reference::run(r),
        cli::Command::Bench(b) => bench::run(b),
        cli::Command::Plan(p) => farm::plan(p),
        cli::Command::Farm(f) => farm::farm(f),
        cli::Command::Assemble(a) => farm::assemble(a),
        cli::Command::View(v) => view::run(v),
    };
    if let Err(e) = result {
        eprintln!("error: {}", one_line(&e));
        std::process::exit(1);
    }
}

/// The whole cause chain on one line. Causes that an outer message already quotes (error
/// types that print their source) are not repeated.
fn one_line(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        let c = c.split_whitespace().collect::<Vec<_>>().join(" ");
        if c.is_empty() || msg.contains(&c) {
            continue;
        }
        if !msg.is_empty() {
            msg.push_str(": ");
        }
        msg.push_str(&c);
    }
    msg
}
