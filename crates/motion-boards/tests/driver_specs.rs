//! Driver configs from hand-made specs: what the server's validation normally keeps out is
//! refused with the key it is about, and a shared link's budget counts every pack on it.

use board_qsb::driver::QsbDriverConfig;
use board_qsb::{QsbDeviceKeys, QsbInputMode, QsbVariant};
use board_spimotor::SpimotorDeviceKeys;
use board_spimotor::driver::SpimotorDriverConfig;
use board_tmcpack::driver::TmcpackDriverConfig;
use board_tmcpack::{TmcpackAxisKeys, TmcpackDeviceKeys};
use motion_drivers::spec::FromSpec as _;
use motion_drivers::spec::{
    AxisMachine, BusPeer, DeviceMachine, Direction, DriverAxis, DriverSignal, DriverSpec, HomeSpec,
    MachineKeys,
};
use motion_drivers::{Model, Pin, SignalKind};

fn axis(channel: usize, machine: AxisMachine) -> DriverAxis {
    DriverAxis {
        channel,
        unit: "mm".to_owned(),
        counts_per_unit: 100.0,
        min: 0.0,
        max: 100.0,
        max_velocity: 10.0,
        max_accel: 100.0,
        home: HomeSpec {
            direction: Direction::Negative,
            max_travel: 125.0,
            position: 0.0,
            input: None,
        },
        machine,
    }
}

fn device(model: Model, machine: DeviceMachine, axes: Vec<DriverAxis>) -> DriverSpec {
    let peer = BusPeer {
        model,
        axes: axes.len(),
        signals: Vec::new(),
        machine: machine.clone(),
    };
    DriverSpec {
        name: "d".to_owned(),
        model,
        line_rate: Some(19_200),
        framing: motion_drivers::LinkFraming::Bytes,
        address: 1,
        machine,
        axes,
        signals: Vec::new(),
        bus: vec![peer],
    }
}

#[test]
fn values_a_board_cannot_take_name_their_key() {
    let mut spimotor = device(
        Model::SPIMOTOR,
        MachineKeys::new(SpimotorDeviceKeys::default()),
        Vec::new(),
    );
    spimotor.address = 0x91; // bit 0 is the read flag
    let error = SpimotorDriverConfig::from_spec(&spimotor).expect_err("odd address");
    assert_eq!((error.channel, error.key), (None, "address"));
    spimotor.address = 0x90;
    assert!(SpimotorDriverConfig::from_spec(&spimotor).is_ok());

    let mut keys = TmcpackAxisKeys::default();
    keys.current.standby = Some(42);
    let pack = device(
        Model::TMCPACK,
        MachineKeys::new(TmcpackDeviceKeys::default()),
        vec![axis(3, MachineKeys::new(keys))],
    );
    let error = TmcpackDriverConfig::from_spec(&pack).expect_err("not a level");
    assert_eq!((error.channel, error.key), (Some(3), "current.standby"));
    assert!(error.to_string().contains("channel 3"));
}

#[test]
fn packs_on_one_link_share_its_polling_budget_and_word_spacing() {
    let slow = TmcpackDeviceKeys {
        packet_timeout_ms: Some(40),
        ..TmcpackDeviceKeys::default()
    };
    let mut pack = device(
        Model::TMCPACK,
        MachineKeys::new(TmcpackDeviceKeys::default()),
        vec![axis(0, MachineKeys::new(TmcpackAxisKeys::default()))],
    );
    pack.bus.push(BusPeer {
        model: Model::TMCPACK,
        axes: 2,
        signals: vec![DriverSignal {
            pin: Pin(0),
            kind: SignalKind::AnalogIn,
        }],
        machine: MachineKeys::new(slow),
    });
    let config = TmcpackDriverConfig::from_spec(&pack).expect("valid");
    // 1 + 2 axes, and one input poll of the other pack.
    assert_eq!(config.bus_motors, 4);
    assert_eq!(config.bus_packet_timeout_units, 20);
    assert!(config.channels[0].is_some() && config.channels[1].is_none());
}

#[test]
fn the_qsb_variant_and_input_mode_reach_the_driver() {
    let keys = QsbDeviceKeys {
        variant: QsbVariant::S,
        input_mode: Some(QsbInputMode::Analog),
        ..QsbDeviceKeys::default()
    };
    let qsb = device(Model::QSB, MachineKeys::new(keys), Vec::new());
    let config = QsbDriverConfig::from_spec(&qsb).expect("valid");
    assert_eq!(config.variant, ::qsb::ProductType::S);
    assert_eq!(config.input_mode, ::qsb::EncoderMode::Analog);
    assert!(!config.motor_drive);
    assert_eq!(QsbVariant::D.digital_io_bits(), 1);
}
