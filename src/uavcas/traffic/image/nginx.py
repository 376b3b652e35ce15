"""One nginx per UAV, serving the image set over HTTP on port 80 of the UAV's own address.

No systemd here (and nothing may touch the host's nginx): each instance gets its own config
with `daemon off` (so the PID we started is nginx itself and we stop it by that PID), a single
process (`master_process off`: half the processes for 20 UAVs), `user root`, and every path
nginx would otherwise take from its compiled-in defaults (pid, logs, temp dirs) under the
run's work directory. `-e` sets the error log before the config is read (nginx >= 1.19.5).
"""

from __future__ import annotations

import socket
from dataclasses import dataclass
from pathlib import Path

HTTP_PORT = 80
TEMP_DIRS = ("client_body", "proxy", "fastcgi", "uwsgi", "scgi")


@dataclass(frozen=True)
class NginxSite:
    node: str
    ip: str
    root: Path  # directory of image files
    work: Path  # this instance's conf/pid/log/temp directory
    port: int = HTTP_PORT
    access_log: bool = False

    @property
    def conf_path(self) -> Path:
        return self.work / "nginx.conf"

    @property
    def error_log(self) -> Path:
        return self.work / "error.log"


def render_conf(site: NginxSite) -> str:
    w = site.work
    temps = "\n".join(f"    {t}_temp_path {w / ('tmp_' + t)};" for t in TEMP_DIRS)
    access = f"access_log {w / 'access.log'};" if site.access_log else "access_log off;"
    return f"""# uavcas: nginx of {site.node} (generated; lives and dies with the run)
daemon off;
master_process off;
worker_processes 1;
user root;
pid {w / 'nginx.pid'};
error_log {site.error_log} warn;
events {{ worker_connections 2048; }}
http {{
    {access}
{temps}
    types {{ image/jpeg jpg; }}
    default_type application/octet-stream;
    sendfile on;
    keepalive_timeout 5s;
    server {{
        listen {site.ip}:{site.port} backlog=1024;
        root {site.root};
        location / {{ }}
    }}
}}
"""


def write_conf(site: NginxSite) -> Path:
    site.work.mkdir(parents=True, exist_ok=True)
    for t in TEMP_DIRS:
        (site.work / f"tmp_{t}").mkdir(exist_ok=True)
    site.conf_path.write_text(render_conf(site))
    return site.conf_path


def argv(site: NginxSite) -> list[str]:
    return ["nginx", "-p", str(site.work), "-e", str(site.error_log), "-c", str(site.conf_path)]


def listening(ns_enter, site: NginxSite, timeout_s: float = 0.2) -> bool:
    """True once a TCP connect to the site succeeds from inside its own namespace.

    `ns_enter` is `uavcas.emulation.kernel.in_netns(ns)`: the socket is created in the node's
    namespace (only this thread moves), so nothing crosses the fabric to check readiness.
    """
    with ns_enter:
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        s.settimeout(timeout_s)
        return s.connect_ex((site.ip, site.port)) == 0
    finally:
        s.close()
