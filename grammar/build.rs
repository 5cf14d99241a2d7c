//! Generates the parser from `src/occam.lalrpop` (the generated file is never committed).

fn main() {
    lalrpop::Configuration::new()
        .use_cargo_dir_conventions()
        .emit_rerun_directives(true)
        .process()
        .expect("the occam grammar must be LR(1)");
}
