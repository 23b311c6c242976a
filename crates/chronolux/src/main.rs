//! `chronolux`: the command line. Arguments and wiring only; no algorithms live here.

mod bench;
mod cli;
mod compare;
mod info;
mod reference;
mod render;
mod scene_input;

use clap::Parser;

fn main() {
    let args = cli::Cli::parse();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    let result = match args.command {
        cli::Command::Render(r) => render::run(r),
        cli::Command::Info(i) => info::run(i),
        cli::Command::Compare(c) => compare::run(c),
        cli::Command::Reference(r) => reference::run(r),
        cli::Command::Bench(b) => bench::run(b),
    };
    if let Err(e) = result {
        // One line, the whole cause chain.
        let msg: Vec<String> = e.chain().map(|c| c.to_string()).collect();
        eprintln!("error: {}", msg.join(": "));
        std::process::exit(1);
    }
}
