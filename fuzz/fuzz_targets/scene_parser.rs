//! Any text given as a scene file: the parser and validator return a scene or an error,
//! never panic. A scene that parses is also meshed when small (the mesher must accept
//! whatever the validator accepts).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(scene) = dfem::scene::parse_str(text, None) {
        if scene.blocks.len() <= 64 {
            let _ = dfem::mesh::build(&scene);
        }
    }
});
