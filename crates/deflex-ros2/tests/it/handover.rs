//! The bounded hand-over queue between the DDS reader and the sensor thread.

use deflex_ros2::handover::Handover;
use std::sync::Arc;
use std::time::Duration;

#[test]
fn full_queue_drops_the_oldest_and_counts() {
    let q = Handover::new(3);
    for i in 0..5 {
        q.push(i);
    }
    assert_eq!(q.dropped(), 2);
    assert_eq!(q.len(), 3);
    let got: Vec<_> = std::iter::from_fn(|| q.pop(Duration::ZERO)).collect();
    assert_eq!(got, vec![2, 3, 4]);
    assert_eq!(q.pop(Duration::from_millis(1)), None);
}

#[test]
fn pop_waits_for_a_push_and_close_wakes_it() {
    let q = Arc::new(Handover::new(2));
    let q2 = q.clone();
    let t = std::thread::spawn(move || q2.pop(Duration::from_secs(10)));
    q.push(7u32);
    assert_eq!(t.join().unwrap(), Some(7));
    let q2 = q.clone();
    let t = std::thread::spawn(move || q2.pop(Duration::from_secs(10)));
    q.close();
    assert_eq!(t.join().unwrap(), None);
}
