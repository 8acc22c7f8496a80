//! `serve`'s access flags: tokens from flags or the environment (the environment keeps them
//! out of `ps` and shell history; Kubernetes passes Secrets that way).

use fovea::server::access::{Access, Secret};

#[derive(clap::Args, Debug)]
pub struct AccessArgs {
    /// Token a client must present to open a session: `Authorization: Bearer TOKEN`, or
    /// `?token=TOKEN` on the page's URL (the page passes it on). Required to listen on a
    /// non-loopback address unless --insecure-no-auth.
    #[arg(long, env = "FOVEA_TOKEN", hide_env_values = true)]
    token: Option<String>,
    /// Token for GET /metrics (Authorization: Bearer). Without one /metrics is open: keep it
    /// inside the cluster (the NetworkPolicy in deploy/k8s does).
    #[arg(long, env = "FOVEA_METRICS_TOKEN", hide_env_values = true)]
    metrics_token: Option<String>,
    /// Token for POST /admin/drain (Authorization: Bearer). Without one the admin endpoints
    /// are off.
    #[arg(long, env = "FOVEA_ADMIN_TOKEN", hide_env_values = true)]
    admin_token: Option<String>,
    /// A folder of token files (`token`, `metrics-token`, `admin-token`; each optional, one
    /// line): a Kubernetes Secret mounted as a volume. A flag or variable given as well wins.
    #[arg(long, value_name = "DIR")]
    token_dir: Option<std::path::PathBuf>,
    /// A browser origin (scheme://host[:port]) allowed to open sessions besides the page's own
    /// (repeatable). Other origins are refused with 403 before the upgrade.
    #[arg(long = "allow-origin", value_name = "ORIGIN")]
    allow_origins: Vec<String>,
    /// Serve on a non-loopback address without a token: anyone who reaches the port gets
    /// sessions. For networks you trust only.
    #[arg(long)]
    insecure_no_auth: bool,
}

impl AccessArgs {
    /// The server's rules, and whether serving without a token was asked for.
    pub fn resolve(self) -> anyhow::Result<(Access, bool)> {
        let dir = self.token_dir.as_deref();
        let pick = |given: Option<String>, file: &str| -> anyhow::Result<Option<Secret>> {
            if let Some(v) = given {
                return Ok(Secret::new(v));
            }
            let Some(dir) = dir else { return Ok(None) };
            let path = dir.join(file);
            match std::fs::read_to_string(&path) {
                // Secrets are small; a large file is a wrong path, not a token.
                Ok(text) if text.len() > 4096 => {
                    anyhow::bail!("{} is over 4 KiB: not a token file", path.display())
                }
                Ok(text) => Ok(Secret::new(text.trim())),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
                Err(e) => Err(anyhow::anyhow!("reading {}: {e}", path.display())),
            }
        };
        Ok((
            Access {
                token: pick(self.token, "token")?,
                metrics_token: pick(self.metrics_token, "metrics-token")?,
                admin_token: pick(self.admin_token, "admin-token")?,
                allow_origins: self.allow_origins,
            },
            self.insecure_no_auth,
        ))
    }
}
