//! Errors of the ROS 2 node.

/// What went wrong starting or running the node.
#[derive(Debug, thiserror::Error)]
pub enum RosError {
    /// A topic name breaks ROS naming rules.
    #[error("bad topic name `{topic}`: {reason}")]
    TopicName {
        /// The name as given.
        topic: String,
        /// Why it was refused.
        reason: String,
    },
    /// The node name or namespace breaks ROS naming rules.
    #[error("bad node name `{name}` in namespace `{namespace}`: {reason}")]
    NodeName {
        /// The node name.
        name: String,
        /// The namespace.
        namespace: String,
        /// Why it was refused.
        reason: String,
    },
    /// The DDS participant, a topic, a publisher or a subscription could not be created (a
    /// domain id above 232 or no usable network interface, for example).
    #[error("cannot start the ROS 2 node ({what}): {reason}")]
    Dds {
        /// What was being created.
        what: String,
        /// The middleware's message.
        reason: String,
    },
    /// A configuration value is out of range.
    #[error("bad node setting {setting}: {reason}")]
    Config {
        /// The setting.
        setting: &'static str,
        /// Why it was refused.
        reason: String,
    },
    /// A worker thread could not be started or ended abnormally.
    #[error("node thread `{thread}`: {reason}")]
    Thread {
        /// The thread's name.
        thread: &'static str,
        /// What happened.
        reason: String,
    },
}

impl RosError {
    pub(crate) fn dds(what: impl Into<String>, reason: impl std::fmt::Debug) -> Self {
        Self::Dds {
            what: what.into(),
            reason: format!("{reason:?}"),
        }
    }
}
