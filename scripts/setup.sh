#!/usr/bin/env bash
# Installs what uavcas needs on a Debian/Ubuntu machine, idempotently:
# system tools (apt, when run as root) and the Python package in ./.venv.
#   scripts/setup.sh            runtime + test extras
#   UAVCAS_NO_APT=1 ...         skip apt (e.g. not root; emulation tests are then skipped)
#   UAVCAS_EXTRAS=test,dl ...   choose the pip extras (dl pulls torch==2.13.0, CPU)
#   UAVCAS_NO_VM=1 ...          skip the guest kernel of `uavcas doctor --vm` (a stock Debian
#                               kernel fetched with apt into /var/cache/uavcas/vm, ~400 MB)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"

APT_PACKAGES=(
  iproute2 nftables iptables ethtool iputils-ping procps psmisc
  tcpdump tshark hping3 nginx-light curl iperf3 ffmpeg
  qemu-system-x86 busybox-static cpio kmod util-linux
  # the report's browser test (tests/report: headless rendering, broken images, console errors);
  # Debian 12: 8 packages, 96 MB download, 301 MB installed (apt-get install --assume-no)
  chromium-headless-shell
)

log() { printf '[setup] %s\n' "$*" >&2; }

if [[ "${UAVCAS_NO_APT:-0}" != "1" ]]; then
  if [[ "$(id -u)" == "0" ]] && command -v apt-get >/dev/null; then
    missing=()
    for p in "${APT_PACKAGES[@]}"; do
      dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if ((${#missing[@]})); then
      log "apt: installing ${missing[*]}"
      # tshark asks whether non-root users may capture; answer without a prompt.
      echo 'wireshark-common wireshark-common/install-setuid boolean false' | debconf-set-selections
      apt-get update -q >/dev/null
      DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}" >/dev/null
    else
      log "apt: all system packages present"
    fi
  else
    log "apt: skipped (not root or no apt-get); emulation features need root and these packages: ${APT_PACKAGES[*]}"
  fi
fi

PY="${PYTHON:-python3}"
if ! "$PY" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
  log "Python >= 3.11 is required (found $("$PY" --version 2>&1))"; exit 2
fi
if [[ ! -x .venv/bin/python ]]; then
  log "creating .venv"
  "$PY" -m venv .venv
fi
extras="${UAVCAS_EXTRAS:-test,dl}"
log "pip: installing uavcas[$extras] into .venv"
.venv/bin/python -m pip install -q --upgrade pip >/dev/null 2>&1 || true
.venv/bin/python -m pip install -q -e ".[$extras]"
# The delay stage's compiled verdict loop (uavcas.emulation.nfqdelay); without a C compiler the
# pure-Python loop runs instead.
if .venv/bin/python -m uavcas.emulation.nfqdelay --build >/dev/null 2>&1; then
  log "delay stage: compiled verdict loop built"
else
  log "delay stage: no C compiler, the pure-Python verdict loop will be used"
fi
if [[ "${UAVCAS_NO_APT:-0}" != "1" && "${UAVCAS_NO_VM:-0}" != "1" && "$(id -u)" == "0" ]] \
    && command -v apt-get >/dev/null; then
  # the kernel `uavcas doctor --vm` boots: apt-get download + dpkg -x + depmod + initramfs;
  # does nothing when the current one is already there
  .venv/bin/python -m uavcas.diagnostics.vm prepare
fi
log "ready: $(.venv/bin/uavcas --version)"
