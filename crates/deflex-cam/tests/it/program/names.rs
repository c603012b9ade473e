//! Names within each language's rules (`deflex_cam::program::names`).

use deflex_cam::program::names::{GCODE_FILE, KRL, RAPID, URSCRIPT, VAL3, is_valid, sanitize};

#[test]
fn names_follow_each_rule() {
    let long = "cone compensated for the TX200 (seed 1) — run 7";
    for rule in [KRL, RAPID, VAL3, URSCRIPT, GCODE_FILE] {
        let name = sanitize(long, &rule);
        assert!(is_valid(&name, &rule), "{} → {name}", rule.language);
        assert!(name.len() <= rule.max_len);
    }
    assert_eq!(sanitize("deflex_cone", &KRL), "deflex_cone");
    assert_eq!(sanitize("7axis", &KRL), "p7axis");
    assert_eq!(sanitize("a b/c", &RAPID), "a_b_c");
    assert_eq!(sanitize("part-1", &GCODE_FILE), "part-1");
    assert_eq!(sanitize("part-1", &RAPID), "part_1");
    assert_eq!(sanitize("", &VAL3), "p");
    // KRL allows 24 characters and no more.
    let krl = sanitize("abcdefghijklmnopqrstuvwxyz", &KRL);
    assert_eq!(krl, "abcdefghijklmnopqrstuvwx");
    // Reserved words are never produced.
    assert_eq!(sanitize("main", &RAPID), "main_prog");
    assert_eq!(sanitize("START", &VAL3), "START_prog");
    assert!(!is_valid("end", &URSCRIPT));
}
