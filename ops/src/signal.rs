//! When a process should stop: SIGTERM (what systemd, Docker and Kubernetes send), Ctrl-C, or —
//! for the processes of an embedded cluster — the end of standard input, which closes when their
//! parent exits, however it exits.

use tracing::warn;

/// Resolves when the process is asked to stop.
pub async fn stop_signal(exit_with_stdin: bool) {
    let stdin_closed = async move {
        if exit_with_stdin {
            use tokio::io::AsyncReadExt;
            let mut buf = [0u8; 64];
            let mut stdin = tokio::io::stdin();
            while matches!(stdin.read(&mut buf).await, Ok(n) if n > 0) {}
        } else {
            std::future::pending::<()>().await;
        }
    };
    let terminate = async {
        #[cfg(unix)]
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut term) => {
                term.recv().await;
            }
            Err(e) => {
                warn!(error = %e, "cannot listen for SIGTERM; stop with Ctrl-C");
                std::future::pending::<()>().await;
            }
        }
        #[cfg(not(unix))]
        std::future::pending::<()>().await;
    };
    tokio::select! {
        _ = terminate => {}
        _ = tokio::signal::ctrl_c() => {}
        _ = stdin_closed => {}
    }
}

/// Resolves once a process's one stop (a watch channel set to true when it stops) turns true:
/// every server and task that ends with the process waits on it.
pub async fn stopped(mut rx: tokio::sync::watch::Receiver<bool>) {
    let _ = rx.wait_for(|s| *s).await;
}
