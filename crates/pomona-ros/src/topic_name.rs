//! ROS topic names as users write them — absolute (`/camera/color/image_raw`), relative to the
//! node's namespace (`camera/image`) or private to the node (`~/detections`) — resolved to the
//! names `ros2-client` takes (it does not expand `~`).

use ros2_client::Name;

use crate::RosError;

/// Resolves `topic` for a node called `node_name` in `namespace` (`/` or `/a/b`).
///
/// # Errors
/// [`RosError::TopicName`] when the name, or the namespace and node name it expands with, breaks
/// ROS naming rules (empty parts, double slashes, characters other than letters, digits and `_`,
/// a part starting with a digit).
pub fn resolve_topic(topic: &str, namespace: &str, node_name: &str) -> Result<Name, RosError> {
    let bad = |reason: String| RosError::TopicName {
        topic: topic.to_owned(),
        reason,
    };
    let full = match topic.strip_prefix("~/") {
        Some(rest) => {
            let ns = namespace.trim_end_matches('/');
            format!("{ns}/{node_name}/{rest}")
        }
        None if topic.starts_with('~') => {
            return Err(bad("a private name starts with `~/`".into()));
        }
        None => topic.to_owned(),
    };
    Name::parse(&full).map_err(|e| bad(format!("{e:?}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn private_absolute_and_relative_names() {
        let name = |t: &str, ns: &str| resolve_topic(t, ns, "pomona").map(|n| n.to_string());
        assert_eq!(
            name("~/detections", "/").ok().as_deref(),
            Some("/pomona/detections")
        );
        assert_eq!(
            name("~/detections", "/robot/arm_a").ok().as_deref(),
            Some("/robot/arm_a/pomona/detections")
        );
        assert_eq!(
            name("/camera/camera/color/image_raw", "/robot")
                .ok()
                .as_deref(),
            Some("/camera/camera/color/image_raw")
        );
        assert_eq!(
            name("camera/info", "/").ok().as_deref(),
            Some("camera/info")
        );
        for bad in ["~detections", "/", "/a//b", "/a/9b", "/a/b-c", ""] {
            let err = name(bad, "/")
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            assert!(err.contains("topic name"), "{bad:?}: {err}");
        }
    }
}
