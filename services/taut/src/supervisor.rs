//! Starts a drone's services as child processes of this executable, reaps and reports deaths,
//! restarts with backoff or stops all (per config), and stops everything on SIGINT/SIGTERM.
//! Children get SIGTERM if the supervisor itself dies (PR_SET_PDEATHSIG), and iceoryx2
//! resources of dead processes are removed on the next start and on shutdown.

use rt_config::{Config, OnDeath, SupervisorConfig};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus};
use std::time::{Duration, Instant};
use taut_ipc::{install_stop_handler, stop_requested};

/// One child service: how to start it and its state.
pub struct ServiceSpec {
    /// Label in reports and the log file's name.
    pub name: String,
    /// Arguments after the executable: `svc <service> --config FILE`, or another verb
    /// (`plant ...` in simulation).
    pub args: Vec<String>,
}

impl ServiceSpec {
    /// `taut svc <service> <args...>`.
    pub fn svc(service: &str, args: Vec<String>) -> Self {
        let mut all = vec!["svc".to_string(), service.to_string()];
        all.extend(args);
        ServiceSpec {
            name: service.to_string(),
            args: all,
        }
    }
}

struct Running {
    spec: ServiceSpec,
    child: Option<Child>,
    started: Instant,
    restarts: u32,
    backoff: Duration,
    restart_at: Option<Instant>,
}

/// What made [`Supervisor::poll`] decide to stop.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    Running,
    /// A service died and policy says stop all (or it died too often).
    Failed(String),
}

pub struct Supervisor {
    exe: PathBuf,
    cfg: SupervisorConfig,
    services: Vec<Running>,
    /// Death reports, for the summary and for tests.
    pub deaths: Vec<String>,
    /// When set, each child's stdout and stderr go to `<dir>/<name>.log` (appended).
    log_dir: Option<PathBuf>,
    /// Services stopped only after every other one has exited (the recorder: it drains what
    /// the others published last).
    stop_last: Vec<String>,
}

impl Supervisor {
    pub fn new(cfg: SupervisorConfig) -> Result<Self, String> {
        let exe =
            std::env::current_exe().map_err(|e| format!("cannot find own executable: {e}"))?;
        Ok(Self {
            exe,
            cfg,
            services: Vec::new(),
            deaths: Vec::new(),
            log_dir: None,
            stop_last: Vec::new(),
        })
    }

    /// Sends every child's output to `<dir>/<name>.log` instead of this terminal.
    pub fn log_to(mut self, dir: &Path) -> Self {
        self.log_dir = Some(dir.to_path_buf());
        self
    }

    fn spawn(&self, spec: &ServiceSpec) -> Result<Child, String> {
        let mut cmd = Command::new(&self.exe);
        cmd.args(&spec.args);
        if let Some(dir) = &self.log_dir {
            let path = dir.join(format!("{}.log", spec.name));
            let log = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&path)
                .map_err(|e| format!("cannot open log {}: {e}", path.display()))?;
            let err = log
                .try_clone()
                .map_err(|e| format!("cannot open log {}: {e}", path.display()))?;
            cmd.stdout(log).stderr(err);
        }
        // SAFETY: prctl is async-signal-safe; it only sets this child's parent-death signal.
        unsafe {
            cmd.pre_exec(|| {
                libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM);
                Ok(())
            });
        }
        cmd.spawn()
            .map_err(|e| format!("cannot start service {}: {e}", spec.name))
    }

    /// Starts `spec` now.
    pub fn start(&mut self, spec: ServiceSpec) -> Result<(), String> {
        let child = self.spawn(&spec)?;
        self.services.push(Running {
            spec,
            child: Some(child),
            started: Instant::now(),
            restarts: 0,
            backoff: Duration::from_secs_f64(self.cfg.backoff_initial_s),
            restart_at: None,
        });
        Ok(())
    }

    /// Reaps dead children, schedules or performs restarts. Call every few tens of ms.
    pub fn poll(&mut self) -> Verdict {
        let now = Instant::now();
        for i in 0..self.services.len() {
            let exited: Option<ExitStatus> = match self.services[i].child.as_mut() {
                Some(c) => c.try_wait().ok().flatten(),
                None => None,
            };
            if let Some(status) = exited {
                let s = &mut self.services[i];
                s.child = None;
                let report = format!("service {} exited: {status}", s.spec.name);
                eprintln!("[launch] {report}");
                self.deaths.push(report.clone());
                if self.cfg.on_death == OnDeath::StopAll {
                    return Verdict::Failed(report);
                }
                if s.restarts >= self.cfg.max_restarts {
                    return Verdict::Failed(format!(
                        "{report}; restarted {} times already (supervisor.max_restarts)",
                        s.restarts
                    ));
                }
                if s.started.elapsed().as_secs_f64() >= self.cfg.healthy_after_s {
                    s.backoff = Duration::from_secs_f64(self.cfg.backoff_initial_s);
                }
                s.restart_at = Some(now + s.backoff);
                eprintln!("[launch] restarting {} in {:?}", s.spec.name, s.backoff);
                s.backoff = (s.backoff * 2).min(Duration::from_secs_f64(self.cfg.backoff_max_s));
            }
            let due = self.services[i].restart_at.is_some_and(|t| t <= now);
            if due {
                match self.spawn(&self.services[i].spec) {
                    Ok(child) => {
                        let s = &mut self.services[i];
                        s.child = Some(child);
                        s.started = now;
                        s.restarts += 1;
                        s.restart_at = None;
                    }
                    Err(e) => return Verdict::Failed(e),
                }
            }
        }
        Verdict::Running
    }

    /// Makes [`Self::stop_all`] stop the service `name` after all the others have exited.
    pub fn stop_last(&mut self, name: &str) {
        self.stop_last.push(name.to_string());
    }

    /// SIGTERM to every child, then SIGKILL to those still alive after `grace`; reaps all.
    /// Those named in [`Self::stop_last`] go in a second round, once the first has exited.
    pub fn stop_all(&mut self, grace: Duration) {
        let last = std::mem::take(&mut self.stop_last);
        self.stop_round(grace, |name| !last.iter().any(|l| l == name));
        self.stop_round(grace, |_| true);
        self.stop_last = last;
        // Whatever a killed child left in shared memory goes now, not at the next start.
        let node = format!("supervisor-{}", std::process::id());
        if let Err(e) = taut_ipc::Ipc::cleanup_dead_nodes(&node) {
            eprintln!("[launch] iceoryx2 cleanup: {e}");
        }
    }

    fn stop_round(&mut self, grace: Duration, pick: impl Fn(&str) -> bool) {
        for s in &self.services {
            if let Some(c) = s.child.as_ref().filter(|_| pick(&s.spec.name)) {
                // SAFETY: kill on our own child's pid.
                unsafe { libc::kill(c.id() as i32, libc::SIGTERM) };
            }
        }
        let deadline = Instant::now() + grace;
        for s in &mut self.services {
            if !pick(&s.spec.name) {
                continue;
            }
            if let Some(mut c) = s.child.take() {
                loop {
                    match c.try_wait() {
                        Ok(Some(_)) | Err(_) => break,
                        Ok(None) if Instant::now() >= deadline => {
                            eprintln!("[launch] {} ignored SIGTERM; killing it", s.spec.name);
                            let _ = c.kill();
                            let _ = c.wait();
                            break;
                        }
                        Ok(None) => std::thread::sleep(Duration::from_millis(10)),
                    }
                }
            }
        }
    }
}

/// The force-sensing chain of one drone (`taut sensor`), started with `config_path`.
pub fn sensor_services(config_path: &Path) -> Vec<ServiceSpec> {
    services(config_path, &["adc-sampler", "tension"])
}

/// Every service of one drone (`taut launch`), in start order. The force estimator runs
/// whatever the controller's tension source, so every flight has the sensor's and the
/// estimator's force to compare.
pub const FLIGHT_SERVICES: [&str; 6] = [
    "adc-sampler",
    "tension",
    "px4-bridge",
    "force-estimator",
    "controller",
    "mission",
];

/// The whole flight stack of one drone, started with `config_path`.
pub fn drone_services(config_path: &Path) -> Vec<ServiceSpec> {
    services(config_path, &FLIGHT_SERVICES)
}

fn services(config_path: &Path, names: &[&str]) -> Vec<ServiceSpec> {
    let cfg = config_path.display().to_string();
    names
        .iter()
        .map(|name| ServiceSpec::svc(name, vec!["--config".into(), cfg.clone()]))
        .collect()
}

/// Waits up to `timeout` for `path` to exist.
pub fn wait_for_file(path: &Path, timeout: Duration) -> bool {
    let end = Instant::now() + timeout;
    while !path.exists() {
        if Instant::now() >= end || stop_requested() {
            return false;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    true
}

/// `taut launch --config FILE`.
pub fn launch(config_path: &Path) -> Result<(), String> {
    let cfg = Config::load(config_path).map_err(|e| e.to_string())?;
    install_stop_handler();
    let mut sup = Supervisor::new(cfg.supervisor)?;
    // The recorder first (it takes every sample from the first) and stopped last.
    let recorder = cfg.recorder.enabled.then_some("recorder");
    if let Some(name) = recorder {
        let ready = std::env::temp_dir().join(format!("taut-launch-{}.ready", std::process::id()));
        let _ = std::fs::remove_file(&ready);
        sup.start(ServiceSpec::svc(
            name,
            vec![
                "--config".into(),
                config_path.display().to_string(),
                "--ready".into(),
                ready.display().to_string(),
            ],
        ))?;
        sup.stop_last(name);
        if !wait_for_file(&ready, Duration::from_secs(10)) {
            eprintln!("[launch] the recorder is not subscribed after 10 s; starting anyway");
        }
        let _ = std::fs::remove_file(&ready);
    }
    for spec in drone_services(config_path) {
        sup.start(spec)?;
    }
    eprintln!(
        "[launch] {}: {}{} running (Ctrl-C to stop)",
        cfg.uav,
        FLIGHT_SERVICES.join(", "),
        if recorder.is_some() { ", recorder" } else { "" }
    );
    let verdict = loop {
        if stop_requested() {
            break Verdict::Running;
        }
        match sup.poll() {
            Verdict::Running => std::thread::sleep(Duration::from_millis(50)),
            failed => break failed,
        }
    };
    sup.stop_all(Duration::from_secs(2));
    match verdict {
        Verdict::Running => {
            eprintln!("[launch] stopped cleanly");
            Ok(())
        }
        Verdict::Failed(why) => Err(why),
    }
}
