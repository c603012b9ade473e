//! Images are embedded in a page ([`deflex_plot::HtmlReport::image`]) as standard base64
//! (RFC 4648 §4, `+` and `/`, with `=` padding): the image's bytes, as the caller's loader
//! gives them, are checked in the page's data URI, whole and exactly.

use deflex_plot::HtmlReport;
use std::path::Path;

/// The data URI of an image file holding `bytes`, as the page embeds it: the encoding alone,
/// between the `base64,` and the closing quote.
fn embedded(bytes: &[u8]) -> String {
    let mut r = HtmlReport::new("t");
    r.image("fig.png", "c");
    let html = r
        .render(|path| {
            assert_eq!(path, Path::new("fig.png"));
            Ok(bytes.to_vec())
        })
        .unwrap();
    let start = html
        .find("src=\"data:image/png;base64,")
        .expect("a data URI")
        + 27;
    let end = start + html[start..].find('"').expect("the closing quote");
    html[start..end].to_string()
}

#[test]
fn rfc4648_test_vectors() {
    // RFC 4648 §10.
    let vectors = [
        ("", ""),
        ("f", "Zg=="),
        ("fo", "Zm8="),
        ("foo", "Zm9v"),
        ("foob", "Zm9vYg=="),
        ("fooba", "Zm9vYmE="),
        ("foobar", "Zm9vYmFy"),
    ];
    for (input, expected) in vectors {
        assert_eq!(embedded(input.as_bytes()), expected, "input {input:?}");
    }
}

#[test]
fn high_bytes_use_plus_and_slash() {
    assert_eq!(embedded(&[0xfb, 0xff, 0xbf]), "+/+/");
    assert_eq!(embedded(&[0, 0, 0]), "AAAA");
}
