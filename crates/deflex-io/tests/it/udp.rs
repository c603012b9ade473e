use core::fmt::Write;
use deflex_io::error::{LinkError, Protocol};
use deflex_io::udp::*;
use std::time::Duration;

#[test]
fn fixed_buf_overflow() {
    let mut b = FixedBuf::<4>::new();
    assert!(write!(b, "abc").is_ok());
    assert!(write!(b, "de").is_err());
    assert!(b.overflowed());
    b.clear();
    assert!(!b.overflowed());
    assert_eq!(b.as_bytes(), b"");
}

#[test]
fn numbers() {
    assert_eq!(parse_f64(b" 1.5 "), Some(1.5));
    assert_eq!(parse_f64(b"-2e3"), Some(-2000.0));
    assert_eq!(parse_f64(b"inf"), None);
    assert_eq!(parse_f64(b"NaN"), None);
    assert_eq!(parse_f64(b""), None);
    assert_eq!(parse_f64(&[0xff, 0x31]), None);
    assert_eq!(parse_u64(b"123"), Some(123));
    assert_eq!(parse_u64(b"+1"), None);
    assert_eq!(parse_u64(b"99999999999999999999999"), None);
}

#[test]
fn zero_timeout_is_a_poll() {
    let mut e = UdpEndpoint::bind("127.0.0.1:0", Protocol::Rsi).unwrap();
    let mut buf = [0u8; 16];
    assert!(e.recv(&mut buf, Duration::ZERO).unwrap().is_none());
    assert!(
        e.recv(&mut buf, Duration::from_millis(1))
            .unwrap()
            .is_none()
    );
    assert!(matches!(e.send(b"x"), Err(LinkError::NoPeer { .. })));
}
