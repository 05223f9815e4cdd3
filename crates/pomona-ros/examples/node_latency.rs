//! Latency and throughput of the ROS 2 node on a real DDS bus (loopback), in one process: a
//! camera publishes a dataset's frames as the RealSense ROS 2 driver would, at `--fps`, in a
//! loop, for `--seconds`; the node detects; a listener receives. Prints one JSON object: the
//! node's latency medians (colour image arrival → detections published, detection alone, and
//! their difference), frames published per second and frames dropped as stale.
//!
//! ```text
//! cargo run --release -p pomona-ros --example node_latency -- DATA \
//!     [--pipeline shape-fit] [--fps 30] [--seconds 20] [--domain 64]
//! ```
//!
//! With the camera slower than detection, latency minus detection time is the node's own cost
//! (decoding, publishing); with the camera faster, frames also wait for the detection under way
//! and the stale ones are dropped.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use pomona_io::Dataset;
use pomona_recording::{CameraInfo, Header, Image, RecordingTopics};
use pomona_ros::vision_msgs::Detection3DArray;
use pomona_ros::{FruitNode, NodeConfig, RosMessage};
use ros2_client::{qos::History, Context, ContextOptions, Name, NodeName, NodeOptions, QosProfile};

fn flag<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> Result<T, String> {
    match args.iter().position(|a| a == name) {
        None => Ok(default),
        Some(i) => args
            .get(i + 1)
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| format!("{name} needs a value")),
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let data = args
        .first()
        .filter(|a| !a.starts_with("--"))
        .ok_or("usage: node_latency DATA [--pipeline P] [--fps F] [--seconds S] [--domain D]")?;
    let pipeline: String = flag(&args, "--pipeline", "shape-fit".to_owned())?;
    let fps: f64 = flag(&args, "--fps", 30.0)?;
    let seconds: f64 = flag(&args, "--seconds", 20.0)?;
    let domain: u16 = flag(&args, "--domain", 64)?;
    if !(fps > 0.0 && seconds > 0.0) {
        return Err("--fps and --seconds must be positive".into());
    }

    let dataset = Dataset::open(data)?;
    let frames = dataset
        .frames()
        .iter()
        .map(|stem| dataset.load_frame(stem))
        .collect::<Result<Vec<_>, _>>()?;
    let (width, height) = frames
        .first()
        .map(|f| (f.camera().width, f.camera().height))
        .ok_or("the dataset has no frames")?;

    let node = FruitNode::start(
        pomona::Detector::builtin(&pipeline)?,
        NodeConfig {
            domain_id: domain,
            ..NodeConfig::default()
        },
    )?;

    let context = Context::with_options(ContextOptions::new().domain_id(domain))?;
    let name = NodeName::new("/", "latency_camera").map_err(|e| format!("{e:?}"))?;
    let mut camera = context.new_node(name, NodeOptions::new())?;
    let qos = QosProfile::publisher_default().history(History::KeepLast { depth: 5 });
    let topics = RecordingTopics::default();
    // The topic `topic` carrying `M`.
    fn topic<M: RosMessage>(
        node: &ros2_client::Node,
        topic: &str,
        qos: &QosProfile,
    ) -> Result<ros2_client::dds::rustdds::Topic, Box<dyn std::error::Error>> {
        let name = Name::parse(topic).map_err(|e| format!("{topic}: {e:?}"))?;
        Ok(node.create_topic(&name, M::type_name(), qos)?)
    }
    let info_topic = topic::<CameraInfo>(&camera, &topics.camera_info, &qos)?;
    let color_topic = topic::<Image>(&camera, &topics.color, &qos)?;
    let depth_topic = topic::<Image>(&camera, &topics.depth, &qos)?;
    let info_pub = camera.create_publisher::<CameraInfo>(&info_topic, Some(qos.clone()))?;
    let color_pub = camera.create_publisher::<Image>(&color_topic, Some(qos.clone()))?;
    let depth_pub = camera.create_publisher::<Image>(&depth_topic, Some(qos.clone()))?;
    let detections_topic = topic::<Detection3DArray>(&camera, &node.topics().detections, &qos)?;
    let listener =
        camera.create_subscription::<Detection3DArray>(&detections_topic, Some(qos.clone()))?;
    let spinner = camera.spinner()?;
    std::thread::spawn(move || smol::block_on(spinner.spin()));
    // Discovery between the participants.
    std::thread::sleep(Duration::from_secs(2));

    let period = Duration::from_secs_f64(1.0 / fps);
    let started = Instant::now();
    let (mut sent, mut received) = (0u64, 0u64);
    let mut next = started;
    while started.elapsed().as_secs_f64() < seconds {
        let frame = &frames[(sent as usize) % frames.len()];
        let stamp_ns = 1_700_000_000_000_000_000 + sent * period.as_nanos() as u64;
        let header = Header::at(stamp_ns, "camera_color_optical_frame");
        info_pub.publish(CameraInfo::from_camera(header.clone(), frame.camera()))?;
        depth_pub.publish(Image::from_depth_16uc1(header.clone(), frame.depth())?)?;
        let color = frame.color().ok_or("the dataset has no colour")?;
        color_pub.publish(Image::from_color(header, color, false))?;
        sent += 1;
        next += period;
        while let Ok(Some(_)) = listener.take() {
            received += 1;
        }
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    std::thread::sleep(Duration::from_secs(1));
    while let Ok(Some(_)) = listener.take() {
        received += 1;
    }
    let run_s = started.elapsed().as_secs_f64();
    let stats = node.shutdown()?;
    let report = serde_json::json!({
        "pipeline": pipeline,
        "data": data,
        "frame_size": [width, height],
        "camera_fps": fps,
        "run_s": run_s,
        "frames_sent": sent,
        "published": stats.published,
        "published_fps": stats.published as f64 / run_s,
        "received_by_listener": received,
        "dropped_stale": stats.dropped_stale,
        "unmatched_color": stats.sync.unmatched_color,
        "failed": stats.failed,
        "last_error": stats.last_error,
        "latency": stats.latency_summary(),
    });
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
