//! The node on a real DDS bus without a ROS installation: in one process, a camera publishing a
//! synthetic dataset's frames as the RealSense driver would, the node, and a listener, all on
//! loopback in a DDS domain of their own per test. What the listener receives must equal what
//! `pomona detect --recording` finds on a recording of the same frames.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::time::{Duration, Instant};

use pomona_core::{Detection, RgbdFrame};
use pomona_io::Dataset;
use pomona_recording::{
    CameraInfo, FrameEncodings, Header, Image, Recording, RecordingTopics, RecordingWriter,
};
use pomona_ros::detection_messages::detection_array;
use pomona_ros::vision_msgs::Detection3DArray;
use pomona_ros::visualization_msgs::{Marker, MarkerArray};
use pomona_ros::{FruitNode, NodeConfig, RosError, RosMessage};
use pomona_synth::{
    generate_dataset, CameraPreset, DatasetSpec, FruitChoice, FruitKind, SceneSpec,
};
use ros2_client::{
    qos::History, Context, ContextOptions, Name, NodeName, NodeOptions, Publisher, QosProfile,
    Subscription,
};

const T0: u64 = 1_700_000_000_000_000_000;
const FRAME_NS: u64 = 33_366_700;
const FRAME_ID: &str = "camera_color_optical_frame";

/// Three synthetic SR4000 apple frames (small: the test builds without optimisation).
fn dataset(root: &Path) -> Dataset {
    let scene = SceneSpec {
        fruit: FruitChoice::Only(FruitKind::Apple),
        camera: CameraPreset::Sr4000.camera(),
        ..SceneSpec::default()
    };
    generate_dataset(&DatasetSpec::new(scene, 3, 7), root, &|_| {}).unwrap();
    Dataset::open(root).unwrap()
}

/// The three messages the driver would publish for `frame` at `stamp_ns`.
fn messages(frame: &RgbdFrame, stamp_ns: u64) -> (CameraInfo, Image, Image) {
    let header = Header::at(stamp_ns, FRAME_ID);
    (
        CameraInfo::from_camera(header.clone(), frame.camera()),
        Image::from_color(header.clone(), frame.color().unwrap(), false),
        Image::from_depth_16uc1(header, frame.depth()).unwrap(),
    )
}

fn reliable() -> QosProfile {
    QosProfile::publisher_default().history(History::KeepLast { depth: 20 })
}

/// A ROS 2 participant of the test: its node spins on a thread of its own until dropped.
struct Participant {
    node: ros2_client::Node,
    _stop: smol::channel::Sender<()>,
}

impl Participant {
    fn new(domain_id: u16, name: &str) -> Self {
        let context = Context::with_options(ContextOptions::new().domain_id(domain_id)).unwrap();
        let mut node = context
            .new_node(NodeName::new("/", name).unwrap(), NodeOptions::new())
            .unwrap();
        let spinner = node.spinner().unwrap();
        let (stop, stopped) = smol::channel::bounded::<()>(1);
        std::thread::spawn(move || {
            let _context = context;
            smol::block_on(futures::future::select(
                std::pin::pin!(spinner.spin()),
                std::pin::pin!(stopped.recv()),
            ));
        });
        Self { node, _stop: stop }
    }

    fn topic<M: RosMessage>(&mut self, topic: &str) -> ros2_client::dds::rustdds::Topic {
        self.node
            .create_topic(&Name::parse(topic).unwrap(), M::type_name(), &reliable())
            .unwrap()
    }

    fn publisher<M: RosMessage>(&mut self, topic: &str) -> Publisher<M> {
        let topic = self.topic::<M>(topic);
        self.node
            .create_publisher(&topic, Some(reliable()))
            .unwrap()
    }

    fn subscription<M: RosMessage>(&mut self, topic: &str) -> Subscription<M> {
        let topic = self.topic::<M>(topic);
        self.node
            .create_subscription(&topic, Some(reliable()))
            .unwrap()
    }
}

/// The camera side: the RealSense ROS 2 driver's three topics.
struct Camera {
    _participant: Participant,
    info: Publisher<CameraInfo>,
    color: Publisher<Image>,
    depth: Publisher<Image>,
}

impl Camera {
    fn new(domain_id: u16) -> Self {
        let mut p = Participant::new(domain_id, "test_camera");
        let topics = RecordingTopics::default();
        Self {
            info: p.publisher(&topics.camera_info),
            color: p.publisher(&topics.color),
            depth: p.publisher(&topics.depth),
            _participant: p,
        }
    }

    fn publish(&self, (info, color, depth): &(CameraInfo, Image, Image)) {
        self.info.publish(info.clone()).unwrap();
        self.depth.publish(depth.clone()).unwrap();
        self.color.publish(color.clone()).unwrap();
    }
}

/// The listener side: the node's detections and markers.
struct Listener {
    _participant: Participant,
    detections: Subscription<Detection3DArray>,
    markers: Subscription<MarkerArray>,
}

impl Listener {
    fn new(domain_id: u16) -> Self {
        let mut p = Participant::new(domain_id, "test_listener");
        Self {
            detections: p.subscription("/pomona/detections"),
            markers: p.subscription("/pomona/markers"),
            _participant: p,
        }
    }

    /// Waits up to `timeout` for the detections of the frame stamped `stamp_ns`.
    fn detections_of(&self, stamp_ns: u64, timeout: Duration) -> Option<Detection3DArray> {
        let until = Instant::now() + timeout;
        while Instant::now() < until {
            match self.detections.take() {
                Ok(Some((array, _))) if array.header.stamp_ns() == Some(stamp_ns) => {
                    return Some(array);
                }
                Ok(Some(_)) => {}
                Ok(None) | Err(_) => std::thread::sleep(Duration::from_millis(5)),
            }
        }
        None
    }

    fn latest_markers(&self) -> Option<MarkerArray> {
        let mut latest = None;
        while let Ok(Some((markers, _))) = self.markers.take() {
            latest = Some(markers);
        }
        latest
    }
}

/// Stamps for published frames, increasing by a frame interval from `T0`.
#[derive(Default)]
struct Clock(std::cell::Cell<u64>);

impl Clock {
    fn next(&self) -> u64 {
        let n = self.0.get();
        self.0.set(n + 1);
        T0 + n * FRAME_NS
    }
}

/// Publishes `frame` until its detections come back; returns them and the stamp they answer.
/// Each attempt carries a new stamp: the first ones can be lost while the participants discover
/// each other (the detections too, published before the listener was matched), and the node
/// ignores a stamp it has already paired.
fn round_trip(
    node: &FruitNode,
    camera: &Camera,
    listener: &Listener,
    clock: &Clock,
    frame: &RgbdFrame,
) -> (Detection3DArray, u64) {
    for _ in 0..40 {
        let stamp = clock.next();
        camera.publish(&messages(frame, stamp));
        if let Some(array) = listener.detections_of(stamp, Duration::from_millis(750)) {
            return (array, stamp);
        }
    }
    panic!(
        "no detections within 30 s of publishing; node: {:?}",
        node.stats()
    );
}

fn config(domain_id: u16) -> NodeConfig {
    NodeConfig {
        domain_id,
        // Every calibrated detection, so the comparison sees low-ranked ones too.
        min_confidence: Some(0.0),
        ..NodeConfig::default()
    }
}

#[test]
fn node_publishes_what_detect_finds_on_a_recording_of_the_same_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let data = dataset(&tmp.path().join("data"));
    let frames: Vec<RgbdFrame> = data
        .frames()
        .iter()
        .map(|stem| data.load_frame(stem).unwrap())
        .collect();

    // What `pomona detect --recording` sees: the frames written to and read from an MCAP file.
    let mcap = tmp.path().join("frames.mcap");
    let mut writer = RecordingWriter::create(&mcap).unwrap();
    for (i, frame) in frames.iter().enumerate() {
        let stamp = T0 + i as u64 * FRAME_NS;
        let topics = RecordingTopics::default();
        writer
            .write_frame(&topics, stamp, FRAME_ID, frame, FrameEncodings::default())
            .unwrap();
    }
    writer.finish().unwrap();
    let recording = Recording::open(&mcap).unwrap();
    let detector = pomona::Detector::builtin("shape-fit").unwrap();
    let expected: Vec<Vec<Detection>> = (0..frames.len())
        .map(|i| {
            let synced = recording.load_frame(i).unwrap();
            assert_eq!(synced.frame_id, FRAME_ID);
            detector
                .detect(&synced.frame)
                .unwrap()
                .into_iter()
                .filter(|d| d.confidence_at_least(0.0))
                .collect()
        })
        .collect();
    let expected_array =
        |i: usize, stamp: u64| detection_array(&Header::at(stamp, FRAME_ID), &expected[i]);
    let found: usize = expected.iter().map(Vec::len).sum();
    assert!(
        found > 0,
        "the frames must hold detections for the comparison to mean anything"
    );

    let domain = 61;
    let node = FruitNode::start(detector, config(domain)).unwrap();
    assert_eq!(node.topics().detections, "/pomona/detections");
    let camera = Camera::new(domain);
    let listener = Listener::new(domain);
    let clock = Clock::default();
    for (i, frame) in frames.iter().enumerate() {
        let (received, stamp) = round_trip(&node, &camera, &listener, &clock, frame);
        assert!(received == expected_array(i, stamp), "frame {i} differs");
    }
    // Markers of the last frame: "delete all", then a shape and a label per detection.
    std::thread::sleep(Duration::from_millis(300));
    let markers = listener.latest_markers().expect("markers");
    assert_eq!(markers.markers[0].action, Marker::DELETE_ALL);
    assert_eq!(markers.markers.len(), 1 + 2 * expected[2].len());

    // A colour image the detector cannot use is counted and named; the node goes on.
    let (info, mut color, depth) = messages(&frames[0], clock.next());
    color.encoding = "mono16".into();
    camera.publish(&(info, color, depth));
    // Wait until the detector has taken it: a good frame arriving first would replace it.
    let until = Instant::now() + Duration::from_secs(30);
    while node.stats().failed == 0 && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(10));
    }
    let (received, stamp) = round_trip(&node, &camera, &listener, &clock, &frames[1]);
    assert!(received == expected_array(1, stamp));
    let stats = node.shutdown().unwrap();
    assert_eq!(stats.failed, 1, "{stats:?}");
    assert!(
        stats
            .last_error
            .as_deref()
            .is_some_and(|e| e.contains("colour image") && e.contains("mono16")),
        "{stats:?}"
    );
    assert!(stats.published >= 4, "{stats:?}");
    assert!(stats.recent.iter().all(|t| t.latency_ms >= t.detect_ms));
}

#[test]
fn slow_detection_works_on_the_newest_frame_and_drops_stale_ones() {
    let tmp = tempfile::tempdir().unwrap();
    let data = dataset(&tmp.path().join("data"));
    let frame = data.load_frame(&data.frames()[0]).unwrap();
    let domain = 62;
    let node = FruitNode::start(
        pomona::Detector::builtin("shape-fit").unwrap(),
        config(domain),
    )
    .unwrap();
    let camera = Camera::new(domain);
    let listener = Listener::new(domain);
    let clock = Clock::default();
    round_trip(&node, &camera, &listener, &clock, &frame);
    let published_before = node.stats().published;

    // A burst far faster than detection: the node must not queue it.
    let burst = 12;
    let mut last = 0;
    for _ in 0..burst {
        last = clock.next();
        camera.publish(&messages(&frame, last));
    }
    assert!(
        listener
            .detections_of(last, Duration::from_secs(30))
            .is_some(),
        "the newest frame of the burst is processed"
    );
    let stats = node.shutdown().unwrap();
    let skipped = stats.dropped_stale + stats.sync.stale_color;
    assert!(stats.published - published_before < burst, "{stats:?}");
    assert!(skipped > 0, "{stats:?}");
    assert_eq!(stats.failed, 0, "{stats:?}");
}

#[test]
fn bad_settings_are_refused_before_joining_the_bus() {
    let detector = || pomona::Detector::builtin("shape-fit").unwrap();
    let refused = |config: NodeConfig| FruitNode::start(detector(), config).err();
    assert!(matches!(
        refused(NodeConfig {
            domain_id: 300,
            ..NodeConfig::default()
        }),
        Some(RosError::Config { .. })
    ));
    assert!(matches!(
        refused(NodeConfig {
            min_confidence: Some(1.5),
            ..NodeConfig::default()
        }),
        Some(RosError::Config { .. })
    ));
    let bad_topic = refused(NodeConfig {
        detections_topic: "/fruit//found".into(),
        ..NodeConfig::default()
    });
    assert!(
        bad_topic
            .as_ref()
            .is_some_and(|e| e.to_string().contains("/fruit//found")),
        "{bad_topic:?}"
    );
    assert!(matches!(
        refused(NodeConfig {
            node_name: "9lives".into(),
            ..NodeConfig::default()
        }),
        Some(RosError::NodeName { .. })
    ));
}
