//! Parses occam files and prints their diagnostics: `cargo run -p occ-grammar --example parse --
//! [-I DIR]... FILE...`. A development aid; `occ check` is the user-facing command.

use std::path::{Path, PathBuf};

struct Files {
    dirs: Vec<PathBuf>,
}

impl occ_grammar::preprocess::Loader for Files {
    fn load(&mut self, name: &str, from: &str) -> Option<(String, String)> {
        let here = Path::new(from).parent().map(Path::to_path_buf);
        here.into_iter().chain(self.dirs.clone()).find_map(|dir| {
            let path = dir.join(name);
            let text = std::fs::read_to_string(&path).ok()?;
            Some((path.display().to_string(), text))
        })
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let mut files = Files { dirs: Vec::new() };
    let mut inputs = Vec::new();
    let print = std::env::var("PRINT").is_ok();
    let all = std::env::var("ALL").is_ok();
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "-I" => files.dirs.extend(args.next().map(PathBuf::from)),
            _ => inputs.push(arg),
        }
    }
    let mut failed = 0;
    for input in &inputs {
        let Ok(text) = std::fs::read_to_string(input) else {
            eprintln!("cannot read {input}");
            continue;
        };
        let parsed = occ_grammar::parse_source(input, &text, &mut files);
        let errors = parsed.has_errors();
        failed += usize::from(errors);
        println!("{input}: {}", if errors { "ERRORS" } else { "ok" });
        for d in parsed.diagnostics.iter().take(if all { 1000 } else { 5 }) {
            let loc = d.locate(&parsed.map);
            let (file, line) = loc
                .map(|l| (parsed.map.files[l.file].path.clone(), l.line))
                .unwrap_or_default();
            println!(
                "  {file}:{line}: {} [{}] {}",
                d.message,
                d.label,
                d.help.clone().unwrap_or_default()
            );
        }
        if print {
            print!("{}", occ_grammar::print::program(&parsed.program));
        }
    }
    println!(
        "{} of {} parsed cleanly",
        inputs.len() - failed,
        inputs.len()
    );
}
