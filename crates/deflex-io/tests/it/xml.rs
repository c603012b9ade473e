use deflex_io::error::LinkError;
use deflex_io::xml::*;

fn all(doc: &[u8]) -> Result<usize, LinkError> {
    let mut s = XmlScanner::new(doc);
    let mut n = 0;
    while let Some(ev) = s.next()? {
        if let XmlEvent::Start { attrs, .. } = ev {
            for a in attrs {
                a?;
            }
        }
        n += 1;
    }
    Ok(n)
}

#[test]
fn scans_elements_attributes_text() {
    let doc = br#"<?xml version="1.0"?><!-- c --><Rob Type='KUKA'><A x = "1" y="2"/><T>  42 </T><![CDATA[raw]]></Rob>"#;
    let mut s = XmlScanner::new(doc);
    match s.next().unwrap().unwrap() {
        XmlEvent::Start { name, attrs, .. } => {
            assert!(name_eq(name, "rob"));
            assert_eq!(attrs.get("type").unwrap(), Some(&b"KUKA"[..]));
        }
        e => panic!("{e:?}"),
    }
    match s.next().unwrap().unwrap() {
        XmlEvent::Start {
            attrs,
            self_closing,
            ..
        } => {
            assert!(self_closing);
            assert_eq!(attrs.get("Y").unwrap(), Some(&b"2"[..]));
            assert_eq!(attrs.get("z").unwrap(), None);
        }
        e => panic!("{e:?}"),
    }
    assert!(matches!(s.next().unwrap(), Some(XmlEvent::Start { .. })));
    assert_eq!(s.next().unwrap(), Some(XmlEvent::Text(b"42")));
    assert!(matches!(s.next().unwrap(), Some(XmlEvent::End { .. })));
    assert_eq!(s.next().unwrap(), Some(XmlEvent::Text(b"raw")));
    assert!(matches!(s.next().unwrap(), Some(XmlEvent::End { .. })));
    assert_eq!(s.next().unwrap(), None);
}

#[test]
fn rejects_malformed() {
    for doc in [
        &b""[..],
        b"<a>",
        b"<a></b>",
        b"</a>",
        b"<a x=1/>",
        b"<a x=\"1/>",
        b"<a x=\"1\"y=\"2\"/>",
        b"<a/><b/>",
        b"text<a/>",
        b"<>",
        b"<a <b/>",
        b"<!-- never closed",
        b"<a></a  x>",
    ] {
        assert!(all(doc).is_err(), "{:?}", String::from_utf8_lossy(doc));
    }
    let deep: Vec<u8> = b"<a>".repeat(MAX_DEPTH + 1);
    assert!(all(&deep).is_err());
}
