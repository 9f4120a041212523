//! Replays the `register_clouds` fuzz target's seeds (`fuzz/seeds/register_clouds/`) and every
//! input it found crashing (`fuzz/regressions/register_clouds/`) through the target's own body
//! (`fuzz/register_clouds.rs`): each must register or fail cleanly, with a finite, rigid answer,
//! a fitness and a confidence in [0, 1], the same answer twice, and a usable registrar after an
//! error.

use arps::{ModelConfig, Registrar, Weights};
use std::path::Path;

include!("../fuzz/register_clouds.rs");

fn inputs(dir: &str) -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz").join(dir);
    let Ok(rd) = std::fs::read_dir(&dir) else { return Vec::new() };
    let mut v: Vec<_> = rd
        .flatten()
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap()))
        .collect();
    v.sort();
    v
}

#[test]
fn seeds_and_regressions_register_or_fail_cleanly() {
    let mut reg = Registrar::new(&Weights::random(&ModelConfig::tiny(), 0).unwrap()).unwrap();
    let seeds = inputs("seeds/register_clouds");
    assert!(seeds.len() >= 9, "the seeds are committed ({} found)", seeds.len());
    for (name, data) in seeds.iter().chain(&inputs("regressions/register_clouds")) {
        eprintln!("{name}");
        register_clouds_target(&mut reg, data);
    }
}

/// The seeds reach the registration (not all rejected before it): most of them give an answer.
#[test]
fn most_seeds_give_an_answer() {
    let mut reg = Registrar::new(&Weights::random(&ModelConfig::tiny(), 0).unwrap()).unwrap();
    let seeds = inputs("seeds/register_clouds");
    let answered = seeds
        .iter()
        .filter(|(_, data)| pair_of(data).is_some_and(|(s, t, o, _)| reg.register(&s, &t, &o).is_ok()))
        .count();
    assert!(answered * 2 > seeds.len(), "{answered} of {} seeds answered", seeds.len());
}
