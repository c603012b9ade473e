//! Messages that show user text ([`deflex_files::shown`]).

use deflex_files::{shown, shown_text};
use std::borrow::Cow;

#[test]
fn control_characters_are_escaped_and_plain_text_is_borrowed() {
    assert!(matches!(shown("L1 µm"), Cow::Borrowed(_)));
    assert_eq!(shown("a\u{1b}[2Jb\r\n\t"), "a\\u{1b}[2Jb\\r\\n\\t");
    assert_eq!(shown_text("line 1\nline\u{7}2"), "line 1\nline\\u{7}2");
    assert_eq!(shown("\u{9b}x"), "\\u{9b}x", "C1 controls too");
}
