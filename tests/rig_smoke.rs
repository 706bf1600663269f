//! The rig itself: an engine without boards ticks and publishes empty frames.

mod support;

use core::time::Duration;

use motion_engine::EngineConfig;
use support::rig::Rig;

#[test]
fn an_empty_engine_ticks() {
    let config = EngineConfig {
        name: "empty".into(),
        tick_hz: 500,
        command_timeout: Duration::from_millis(100),
        links: vec![],
        devices: vec![],
        axes: vec![],
        ..EngineConfig::default()
    };
    let mut rig = Rig::new(config, vec![], vec![]);
    rig.run(10);
    assert_eq!(rig.frame.tick, 9);
    assert_eq!(rig.now, Duration::from_millis(20));
}
