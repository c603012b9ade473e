//! What every exporter shares (`deflex_cam::program::common`): comments wrapped at words.

use deflex_cam::program::common::wrap;

#[test]
fn comments_wrap_at_words() {
    let text = "predicted error 2.1548 mm uncompensated, 0.0001 mm compensated; largest compensation 2.2938 mm";
    let lines = wrap(text, 40);
    assert!(lines.iter().all(|l| l.chars().count() <= 40), "{lines:?}");
    assert_eq!(lines.join(" "), text, "no word cut or lost");
    assert_eq!(wrap("abcdefghij", 4), ["abcd", "efgh", "ij"]);
    assert_eq!(wrap("", 10), [""]);
}
