//! The one line `pomona` prints for a failed command: the error's context chain, outermost
//! first, joined by `: `.
//!
//! Library errors name the file and quote their cause in their own message (`{path}: {source}`)
//! *and* expose it as `source()`, so printing every link of the chain would say the cause
//! twice. A link whose text the line already ends with is skipped.

/// The error and its causes as one line, without repeated causes.
pub fn error_line(err: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if line.ends_with(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("{path}: {source}")]
    struct Quoting {
        path: String,
        source: std::io::Error,
    }

    #[test]
    fn causes_quoted_by_their_parent_are_not_repeated() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let err = anyhow::Error::new(Quoting {
            path: "/tmp/m.json".into(),
            source: io,
        })
        .context("loading the model");
        assert_eq!(
            error_line(&err),
            "loading the model: /tmp/m.json: no such file"
        );
        let plain = anyhow::anyhow!("inner").context("outer");
        assert_eq!(error_line(&plain), "outer: inner");
    }
}
