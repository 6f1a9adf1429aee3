//! The lead among several coordinators on one PostgreSQL store: one leads (serves workers,
//! clients and the studio, and writes the store), the others stand by and take over when its
//! lead lapses, rebuilding the scheduler from the store.
//!
//! * **The lease** is one row in the database (`restauro_leader`): its holder, its epoch and
//!   when it expires, by the database's clock. A standby takes it once it has expired, with an
//!   epoch one more than any before; the leader renews it every third of its time to live.
//! * **Stepping down by its own clock.** The leader counts its lead as valid until two thirds of
//!   the time to live after it sent its last successful renewal, on its monotonic clock: well
//!   before the database would expire it, so two coordinators never both believe they lead,
//!   whatever either clock says. A leader that cannot renew in time stops serving.
//! * **Fencing.** The epoch is the fencing token: every write to the store checks it under a
//!   share lock of the lead row, so a leader that lost its lead (paused, cut off) writes
//!   nothing once another has taken it, and the taker waits for writes under the old epoch to
//!   end. It is also the lease-signing epoch (`lease`), so a worker's results under the old
//!   leader are taken by the new one.
//!
//! No advisory locks (their life is a session's, which pools and cancelled sessions blur) and
//! no consensus of our own: the database's row lock and clock decide. A file store (redb) has
//! one coordinator, which always leads: the file's lock keeps out another.

use crate::store::{LeadAttempt, Store};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::watch;
use tracing::{info, warn};

/// Who a coordinator is in the lead row, and how long a lead lives unrenewed.
#[derive(Clone, Debug)]
pub struct LeadConfig {
    /// This coordinator, unique to its process (host, process id, a random part).
    pub holder: String,
    pub ttl: Duration,
}

impl LeadConfig {
    /// A holder name for this process: its host, its process id and a random part (so that a
    /// restarted process never passes for the one before), and where it serves.
    pub fn for_process(serves: &str, ttl: Duration) -> LeadConfig {
        let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
            .ok()
            .or_else(|| std::env::var("HOSTNAME").ok())
            .map(|h| h.trim().to_owned())
            .filter(|h| !h.is_empty())
            .unwrap_or_else(|| "localhost".into());
        let nonce = crate::ids::random_secret();
        let nonce: String = nonce[..4].iter().map(|b| format!("{b:02x}")).collect();
        let holder = format!("{host} pid {} {nonce} serving {serves}", std::process::id());
        LeadConfig { holder, ttl }
    }

    /// How often a standby tries to take the lead: often enough to take over within a second
    /// or so of its lapse.
    fn standby_poll(&self) -> Duration {
        (self.ttl / 6).clamp(Duration::from_millis(100), Duration::from_secs(1))
    }
}

/// What a standby tells its readiness probe while it waits.
pub type StandbyState = Arc<Mutex<String>>;

/// A lead this coordinator holds: until [`Lead::lost`] resolves.
pub struct Lead {
    /// `None` for a file store: the only coordinator, leading for good.
    held: Option<Held>,
}

struct Held {
    renewal: Arc<Renewal>,
    /// Why the lead was lost, once it was.
    lost: watch::Receiver<Option<String>>,
}

/// What the lead's two threads share: the renewer, which renews the lead every third of its
/// time to live, and the watchdog, which says the lead is lost once its deadline passes on this
/// process's clock — even while a renewal hangs (the database cut off).
struct Renewal {
    store: Arc<Store>,
    config: LeadConfig,
    epoch: u64,
    /// The lead is this coordinator's until this instant: two thirds of the time to live
    /// after the last successful renewal was sent.
    deadline: Mutex<Instant>,
    stop: std::sync::atomic::AtomicBool,
    lost: watch::Sender<Option<String>>,
}

/// Takes the lead if it is free (at once for a file store); else says in `state` (and the log,
/// once for each change) who holds it, or why it cannot be taken (the store unreachable: the
/// coordinator stands by and tries again).
pub async fn try_once(
    store: &Arc<Store>,
    config: &LeadConfig,
    state: &StandbyState,
) -> Option<Lead> {
    if !store.has_leads() {
        return Some(Lead { held: None });
    }
    let (s, c) = (store.clone(), config.clone());
    let attempt = tokio::task::spawn_blocking(move || s.try_lead(&c.holder, c.ttl))
        .await
        .expect("the attempt does not panic");
    let why = match attempt {
        Ok(LeadAttempt::Led { epoch }) => {
            info!(epoch, holder = %config.holder, "this coordinator leads");
            return Some(Lead::hold(store.clone(), config.clone(), epoch));
        }
        Ok(LeadAttempt::HeldBy { holder, for_ms }) => {
            format!("standby: {holder} leads (for {:.1} s unrenewed)", for_ms as f64 / 1e3)
        }
        Err(e) => format!("standby: {e}"),
    };
    let mut shown = state.lock().unwrap_or_else(|p| p.into_inner());
    // Said once for each holder, not at every attempt.
    let who = |text: &str| text.split(" (for ").next().unwrap_or_default().to_owned();
    if who(&shown) != who(&why) {
        info!("{why}");
    }
    *shown = why;
    None
}

/// Waits until this coordinator leads on `store` (at once for a file store): `None` when
/// `stop` came first. While it waits, `state` says who leads.
pub async fn take(
    store: &Arc<Store>,
    config: &LeadConfig,
    state: &StandbyState,
    stop: &mut watch::Receiver<bool>,
) -> Option<Lead> {
    loop {
        if let Some(lead) = try_once(store, config, state).await {
            return Some(lead);
        }
        tokio::select! {
            () = tokio::time::sleep(config.standby_poll()) => {}
            _ = stop.wait_for(|stopping| *stopping) => return None,
        }
    }
}

impl Lead {
    fn hold(store: Arc<Store>, config: LeadConfig, epoch: u64) -> Lead {
        let (lost_tx, lost) = watch::channel(None);
        let renewal = Arc::new(Renewal {
            deadline: Mutex::new(Instant::now() + config.ttl * 2 / 3),
            store,
            config,
            epoch,
            stop: Default::default(),
            lost: lost_tx,
        });
        // Both end by themselves once the lead is given up or lost.
        for (name, run) in
            [("lead-renewer", Renewal::renew as fn(&Renewal)), ("lead-watchdog", Renewal::watch)]
        {
            let renewal = renewal.clone();
            std::thread::Builder::new()
                .name(name.into())
                .spawn(move || run(&renewal))
                .expect("starting a thread of the lead");
        }
        Lead { held: Some(Held { renewal, lost }) }
    }

    /// The lead's epoch (`None` for a file store's sole coordinator).
    pub fn epoch(&self) -> Option<u64> {
        self.held.as_ref().map(|h| h.renewal.epoch)
    }

    /// Resolves when the lead is lost, saying why; never for a file store.
    pub async fn lost(&self) -> String {
        let Some(held) = &self.held else { return std::future::pending().await };
        let mut lost = held.lost.clone();
        match lost.wait_for(Option::is_some).await {
            Ok(why) => why.clone().unwrap_or_default(),
            Err(_) => "the lead's renewer stopped".into(),
        }
    }

    /// Gives the lead up (a stop asked for): a standby takes over at once rather than when
    /// the lead would lapse. Waits a third of the time to live at most: a database that does
    /// not answer (cut off) lets the lead lapse by itself, and the stop is not held up.
    pub fn release(self) {
        let Some(held) = self.held else { return };
        let renewal = held.renewal;
        renewal.stop.store(true, Ordering::SeqCst);
        if renewal.lost.borrow().is_some() {
            return;
        }
        let patience = renewal.config.ttl / 3;
        let (said, told) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let r = &renewal;
            let _ = said.send((r.epoch, r.store.release_lead(&r.config.holder, r.epoch)));
        });
        match told.recv_timeout(patience) {
            Ok((epoch, Ok(()))) => info!(epoch, "gave the lead up"),
            Ok((_, Err(e))) => warn!("could not give the lead up ({e}); it lapses by itself"),
            Err(_) => warn!("the store did not answer; the lead lapses by itself"),
        }
    }
}

impl Renewal {
    fn over(&self) -> bool {
        self.stop.load(Ordering::SeqCst) || self.lost.borrow().is_some()
    }

    fn deadline(&self) -> std::sync::MutexGuard<'_, Instant> {
        self.deadline.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Renews the lead every third of its time to live; a refused renewal loses it.
    fn renew(&self) {
        let (ttl, every) = (self.config.ttl, self.config.ttl / 3);
        let mut next = Instant::now() + every;
        while !self.over() {
            let now = Instant::now();
            if now < next {
                std::thread::sleep((next - now).min(Duration::from_millis(50)));
                continue;
            }
            let sent = Instant::now();
            next = sent + every;
            match self.store.renew_lead(&self.config.holder, self.epoch, ttl) {
                Ok(true) => *self.deadline() = sent + ttl * 2 / 3,
                Ok(false) => {
                    self.lost.send_replace(Some(format!(
                        "another coordinator took the lead (this one's epoch was {})",
                        self.epoch
                    )));
                }
                Err(e) => {
                    warn!("renewing the lead failed: {e}; trying again");
                    next = sent + every / 4;
                }
            }
        }
    }

    /// Says the lead is lost once its deadline passes unrenewed.
    fn watch(&self) {
        while !self.over() {
            let (until, now) = (*self.deadline(), Instant::now());
            if now >= until {
                self.lost.send_replace(Some(format!(
                    "no renewal of the lead succeeded within {:.1} s (two thirds of its time to \
                     live): stepping down before the database would let another coordinator \
                     take it",
                    self.config.ttl.as_secs_f64() * 2.0 / 3.0
                )));
                return;
            }
            std::thread::sleep((until - now).min(Duration::from_millis(50)));
        }
    }
}

/// The operations endpoint of a standby: alive, never ready (readiness is the leader's alone,
/// so a Service sends nothing here), saying who leads; `restauro_coordinator_standby` is 1.
pub struct StandbyProbe {
    state: StandbyState,
    registry: prometheus_client::registry::Registry,
}

impl StandbyProbe {
    pub fn new(state: StandbyState) -> StandbyProbe {
        let mut registry = prometheus_client::registry::Registry::default();
        let standby = prometheus_client::metrics::gauge::Gauge::<i64>::default();
        standby.set(1);
        registry.register(
            "restauro_coordinator_standby",
            "1 while this coordinator stands by for the lead",
            standby,
        );
        StandbyProbe { state, registry }
    }
}

impl restauro_ops::endpoint::Probe for StandbyProbe {
    fn registry(&self) -> &prometheus_client::registry::Registry {
        &self.registry
    }

    fn ready(&self) -> Result<(), restauro_ops::endpoint::NotReady> {
        let why = self.state.lock().unwrap_or_else(|p| p.into_inner()).clone();
        Err(restauro_ops::endpoint::NotReady(why))
    }
}
