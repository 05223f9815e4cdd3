//! The ROS 2 node: colour, aligned depth and camera info in; `vision_msgs/Detection3DArray` and
//! RViz markers out.
//!
//! Two threads, so that receiving never waits for detection:
//! * **`pomona-dds`** runs the middleware (the node's spinner and one task per subscription) and
//!   pairs messages with [`LiveSync`]; each synchronised frame goes into a one-slot
//!   [`LatestFrame`] mailbox, replacing a frame the detector has not started (counted as
//!   dropped): when detection is slower than the camera, the node works on the newest frame.
//! * **`pomona-detect`** takes frames from the mailbox, decodes them exactly as
//!   `pomona detect --recording` does (so a recorded topic gives the same detections), detects,
//!   filters by confidence and publishes, stamped with the colour image's header.
//!
//! Subscriptions use the ROS 2 sensor-data profile (best effort, keep last 5), publications are
//! reliable (keep last 10). Latency is measured from the arrival of the colour image to the
//! publication of its detections.

use std::collections::VecDeque;
use std::pin::pin;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::Instant;

use futures::StreamExt;
use pomona::{Detector, KeepRule};
use pomona_core::{Detection, RgbdFrame};
use pomona_recording::{CameraInfo, Image};
use ros2_client::{
    qos::History, Context, ContextOptions, Name, Node, NodeName, NodeOptions, Publisher,
    QosProfile, Subscription,
};

use crate::detection_messages::{detection_array, marker_array};
use crate::latest_frame::LatestFrame;
use crate::live_sync::{FrameMessages, LiveSync, SyncCounts};
use crate::topic_name::resolve_topic;
use crate::vision_msgs::Detection3DArray;
use crate::visualization_msgs::MarkerArray;
use crate::{NodeConfig, RosError, RosMessage};

/// Time spent on one published frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameTiming {
    /// The colour image's stamp, nanoseconds since the epoch.
    pub stamp_ns: u64,
    /// From the colour image's arrival to its detections' publication, ms.
    pub latency_ms: f64,
    /// Decoding the messages into a frame, ms.
    pub decode_ms: f64,
    /// Detection alone, ms.
    pub detect_ms: f64,
    /// Detections published.
    pub detections: usize,
}

impl NodeStats {
    /// Medians of [`NodeStats::recent`] (`None` before the first published frame).
    pub fn latency_summary(&self) -> Option<crate::LatencySummary> {
        crate::LatencySummary::of(&self.recent)
    }
}

/// What the node has done so far.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NodeStats {
    /// Messages received on the colour, depth and camera-info topics.
    pub received: [u64; 3],
    /// What the synchroniser paired and dropped.
    pub sync: SyncCounts,
    /// Synchronised frames replaced in the mailbox before the detector took them.
    pub dropped_stale: u64,
    /// Frames whose detections were published.
    pub published: u64,
    /// Frames that failed (undecodable message, detector error, publication error).
    pub failed: u64,
    /// The latest failure's message.
    pub last_error: Option<String>,
    /// Timings of the most recent published frames, oldest first.
    pub recent: Vec<FrameTiming>,
}

#[derive(Debug, Default)]
struct Counters {
    received: [u64; 3],
    published: u64,
    failed: u64,
    last_error: Option<String>,
    recent: VecDeque<FrameTiming>,
}

struct Shared {
    sync: Mutex<LiveSync<Instant>>,
    mailbox: LatestFrame<FrameMessages<Instant>>,
    counters: Mutex<Counters>,
    timing_window: usize,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

impl Shared {
    fn fail(&self, message: String) {
        let mut c = lock(&self.counters);
        c.failed += 1;
        c.last_error = Some(message);
    }
}

/// The resolved topic names a node uses.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeTopics {
    /// Colour, depth and camera-info subscriptions.
    pub input: [String; 3],
    /// Detection output.
    pub detections: String,
    /// Marker output, when published.
    pub markers: Option<String>,
}

/// A running node; [`FruitNode::shutdown`] stops it (dropping it stops it too, without
/// reporting).
pub struct FruitNode {
    shared: Arc<Shared>,
    stop: Option<smol::channel::Sender<()>>,
    dds: Option<JoinHandle<()>>,
    detect: Option<JoinHandle<()>>,
    topics: NodeTopics,
}

impl std::fmt::Debug for FruitNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FruitNode")
            .field("topics", &self.topics)
            .finish_non_exhaustive()
    }
}

/// The ROS 2 sensor-data profile: best effort, volatile, keep last 5.
fn sensor_data_qos() -> QosProfile {
    QosProfile::subscription_default().history(History::KeepLast { depth: 5 })
}

fn output_qos() -> QosProfile {
    QosProfile::publisher_default().history(History::KeepLast { depth: 10 })
}

/// Creates the topic `name` carrying `M` with `qos`; `what` names the endpoint in errors.
fn topic_for<M: RosMessage>(
    node: &mut Node,
    name: &Name,
    qos: &QosProfile,
    what: &str,
) -> Result<ros2_client::dds::rustdds::Topic, RosError> {
    node.create_topic(name, M::type_name(), qos)
        .map_err(|e| RosError::dds(what, e))
}

fn subscribe<M: RosMessage>(node: &mut Node, name: &Name) -> Result<Subscription<M>, RosError> {
    let what = format!("subscription to {name}");
    let topic = topic_for::<M>(node, name, &sensor_data_qos(), &what)?;
    node.create_subscription::<M>(&topic, Some(sensor_data_qos()))
        .map_err(|e| RosError::dds(what, e))
}

fn advertise<M: RosMessage>(node: &mut Node, name: &Name) -> Result<Publisher<M>, RosError> {
    let what = format!("publisher on {name}");
    let topic = topic_for::<M>(node, name, &output_qos(), &what)?;
    node.create_publisher::<M>(&topic, Some(output_qos()))
        .map_err(|e| RosError::dds(what, e))
}

struct Outputs {
    detections: Publisher<Detection3DArray>,
    markers: Option<Publisher<MarkerArray>>,
}

impl FruitNode {
    /// Starts a node running `detector` with `config`: joins the DDS domain, subscribes and
    /// advertises, and returns at once (frames are processed on the node's threads).
    ///
    /// # Errors
    /// [`RosError::Config`] for a bad setting or a minimum confidence the model cannot apply
    /// (it has no calibration); [`RosError::TopicName`] / [`RosError::NodeName`] for names that
    /// break ROS rules; [`RosError::Dds`] when the middleware cannot start;
    /// [`RosError::Thread`] when a thread cannot be spawned.
    pub fn start(detector: Detector, config: NodeConfig) -> Result<Self, RosError> {
        config.validate()?;
        let keep = detector
            .keep_rule_for(config.min_confidence)
            .map_err(|e| RosError::Config {
                setting: "minimum confidence",
                reason: e.to_string(),
            })?;
        let node_name = NodeName::new(&config.namespace, &config.node_name).map_err(|e| {
            RosError::NodeName {
                name: config.node_name.clone(),
                namespace: config.namespace.clone(),
                reason: format!("{e:?}"),
            }
        })?;
        let resolve = |t: &str| resolve_topic(t, &config.namespace, &config.node_name);
        let input = [
            resolve(&config.input.color)?,
            resolve(&config.input.depth)?,
            resolve(&config.input.camera_info)?,
        ];
        let detections_name = resolve(&config.detections_topic)?;
        let markers_name = config.markers_topic.as_deref().map(resolve).transpose()?;
        let topics = NodeTopics {
            input: input.clone().map(|n| n.to_string()),
            detections: detections_name.to_string(),
            markers: markers_name.as_ref().map(Name::to_string),
        };

        let context = Context::with_options(ContextOptions::new().domain_id(config.domain_id))
            .map_err(|e| RosError::dds("DDS participant", e))?;
        let mut node = context
            .new_node(node_name, NodeOptions::new())
            .map_err(|e| RosError::dds("node", e))?;
        let [color_name, depth_name, info_name] = &input;
        let color_sub = subscribe::<Image>(&mut node, color_name)?;
        let depth_sub = subscribe::<Image>(&mut node, depth_name)?;
        let info_sub = subscribe::<CameraInfo>(&mut node, info_name)?;
        let outputs = Outputs {
            detections: advertise(&mut node, &detections_name)?,
            markers: markers_name
                .as_ref()
                .map(|name| advertise(&mut node, name))
                .transpose()?,
        };
        let spinner = node.spinner().map_err(|e| RosError::dds("spinner", e))?;

        let shared = Arc::new(Shared {
            sync: Mutex::new(LiveSync::new(config.sync_tolerance_ns)),
            mailbox: LatestFrame::default(),
            counters: Mutex::new(Counters::default()),
            timing_window: config.timing_window,
        });
        let (stop, stopped) = smol::channel::bounded::<()>(1);

        let dds = {
            let shared = Arc::clone(&shared);
            std::thread::Builder::new()
                .name("pomona-dds".into())
                .spawn(move || {
                    // The node and context live as long as the thread: dropping them leaves the
                    // DDS domain cleanly.
                    let _node = node;
                    let _context = context;
                    let executor = smol::LocalExecutor::new();
                    executor.spawn(spinner.spin()).detach();
                    let receive = receive_loops(&shared, &color_sub, &depth_sub, &info_sub);
                    smol::block_on(executor.run(async {
                        futures::future::select(pin!(receive), pin!(stopped.recv())).await;
                    }));
                    shared.mailbox.close();
                })
                .map_err(|e| RosError::Thread {
                    thread: "pomona-dds",
                    reason: e.to_string(),
                })?
        };
        let detect = {
            let shared = Arc::clone(&shared);
            std::thread::Builder::new()
                .name("pomona-detect".into())
                .spawn(move || detect_loop(&shared, &detector, keep, &outputs))
                .map_err(|e| RosError::Thread {
                    thread: "pomona-detect",
                    reason: e.to_string(),
                })?
        };
        Ok(Self {
            shared,
            stop: Some(stop),
            dds: Some(dds),
            detect: Some(detect),
            topics,
        })
    }

    /// The topics the node subscribes to and publishes on, fully resolved.
    pub fn topics(&self) -> &NodeTopics {
        &self.topics
    }

    /// A snapshot of the node's counters and recent timings.
    pub fn stats(&self) -> NodeStats {
        let counters = lock(&self.shared.counters);
        NodeStats {
            received: counters.received,
            sync: lock(&self.shared.sync).counts(),
            dropped_stale: self.shared.mailbox.replaced(),
            published: counters.published,
            failed: counters.failed,
            last_error: counters.last_error.clone(),
            recent: counters.recent.iter().copied().collect(),
        }
    }

    /// Stops receiving, lets the detector finish the frame it is on (a frame waiting in the
    /// mailbox is still processed), leaves the DDS domain and returns the final counters.
    ///
    /// # Errors
    /// [`RosError::Thread`] when a node thread panicked.
    pub fn shutdown(mut self) -> Result<NodeStats, RosError> {
        self.stop_threads()?;
        Ok(self.stats())
    }

    fn stop_threads(&mut self) -> Result<(), RosError> {
        // Closing the channel ends the receive loop; the DDS thread then closes the mailbox.
        self.stop.take();
        for (thread, handle) in [
            ("pomona-dds", self.dds.take()),
            ("pomona-detect", self.detect.take()),
        ] {
            if let Some(handle) = handle {
                handle.join().map_err(|_| RosError::Thread {
                    thread,
                    reason: "panicked".into(),
                })?;
            }
        }
        Ok(())
    }
}

impl Drop for FruitNode {
    fn drop(&mut self) {
        // Errors cannot be reported from drop; `shutdown` reports them.
        let _ = self.stop_threads();
    }
}

/// Receives the three topics until a stream ends, pairing frames into the mailbox.
async fn receive_loops(
    shared: &Shared,
    color: &Subscription<Image>,
    depth: &Subscription<Image>,
    info: &Subscription<CameraInfo>,
) {
    let count = |topic: usize| lock(&shared.counters).received[topic] += 1;
    let deliver = |frame: Option<FrameMessages<Instant>>| {
        if let Some(frame) = frame {
            shared.mailbox.put(frame);
        }
    };
    let colors = color.async_stream().for_each(|message| async {
        match message {
            Ok((image, _)) => {
                count(0);
                let frame = lock(&shared.sync).push_color(image, Instant::now());
                deliver(frame);
            }
            Err(e) => shared.fail(format!("colour message: {e:?}")),
        }
    });
    let depths = depth.async_stream().for_each(|message| async {
        match message {
            Ok((image, _)) => {
                count(1);
                let frame = lock(&shared.sync).push_depth(image);
                deliver(frame);
            }
            Err(e) => shared.fail(format!("depth message: {e:?}")),
        }
    });
    let infos = info.async_stream().for_each(|message| async {
        match message {
            Ok((camera_info, _)) => {
                count(2);
                let frame = lock(&shared.sync).push_info(camera_info);
                deliver(frame);
            }
            Err(e) => shared.fail(format!("camera info message: {e:?}")),
        }
    });
    futures::join!(colors, depths, infos);
}

/// Decodes a synchronised frame as `pomona detect --recording` does for a recorded one.
///
/// # Errors
/// A message that does not give an image or camera (unsupported encoding, sizes that disagree),
/// as a line naming the message.
pub fn decode_frame(messages: &FrameMessages<impl Sized>) -> Result<RgbdFrame, String> {
    let stamp = messages.color.header.stamp_ns().unwrap_or(0);
    let camera = messages
        .info
        .to_camera()
        .map_err(|e| format!("camera info for frame {stamp}: {e}"))?;
    let color = messages
        .color
        .to_color()
        .map_err(|e| format!("colour image {stamp}: {e}"))?;
    let depth = messages
        .depth
        .to_depth()
        .map_err(|e| format!("depth image for frame {stamp}: {e}"))?;
    RgbdFrame::new(camera, depth, Some(color)).map_err(|e| format!("frame {stamp}: {e}"))
}

fn detect_loop(shared: &Shared, detector: &Detector, keep: KeepRule, outputs: &Outputs) {
    while let Some(messages) = shared.mailbox.take() {
        let started = Instant::now();
        let frame = match decode_frame(&messages) {
            Ok(frame) => frame,
            Err(e) => {
                shared.fail(e);
                continue;
            }
        };
        let decoded = Instant::now();
        let detections = match detector.detect(&frame) {
            Ok(d) => d,
            Err(e) => {
                shared.fail(format!("detection: {e}"));
                continue;
            }
        };
        let detected = Instant::now();
        let kept: Vec<Detection> = detections.into_iter().filter(|d| keep.keeps(d)).collect();
        let header = &messages.color.header;
        let mut published = outputs
            .detections
            .publish(detection_array(header, &kept))
            .map_err(|e| format!("detections: {e:?}"));
        if let (Ok(()), Some(markers)) = (&published, &outputs.markers) {
            published = markers
                .publish(marker_array(header, &kept))
                .map_err(|e| format!("markers: {e:?}"));
        }
        let done = Instant::now();
        if let Err(e) = published {
            shared.fail(format!("publishing: {e:?}"));
            continue;
        }
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        let timing = FrameTiming {
            stamp_ns: header.stamp_ns().unwrap_or(0),
            latency_ms: ms(messages.color_tag, done),
            decode_ms: ms(started, decoded),
            detect_ms: ms(decoded, detected),
            detections: kept.len(),
        };
        let mut counters = lock(&shared.counters);
        counters.published += 1;
        counters.recent.push_back(timing);
        while counters.recent.len() > shared.timing_window {
            counters.recent.pop_front();
        }
    }
}
