//! The `.hair` and TressFX readers on arbitrary bytes: an error or a model of finite strands,
//! never a panic (and, under the fuzzer's memory limit, never an allocation the file cannot
//! back).
#![no_main]

use hairsim_files::hairfile::{read_hair, read_tfx, ReadOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let options = ReadOptions::default();
    for model in [read_hair(bytes, &options), read_tfx(bytes, &options)]
        .into_iter()
        .flatten()
    {
        assert!(model.strands.iter().flatten().all(|p| p.is_finite()));
    }
    let resampled = ReadOptions {
        nodes: Some(9),
        ..ReadOptions::default()
    };
    if let Ok(model) = read_hair(bytes, &resampled) {
        assert!(model.strands.iter().all(|s| s.len() == 9));
    }
});
