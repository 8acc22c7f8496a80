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
    pub fn resolve(self) -> (Access, bool) {
        let secret = |v: Option<String>| v.and_then(Secret::new);
        (
            Access {
                token: secret(self.token),
                metrics_token: secret(self.metrics_token),
                admin_token: secret(self.admin_token),
                allow_origins: self.allow_origins,
            },
            self.insecure_no_auth,
        )
    }
}
