"""Unit tests of the apps (no root): payloads, configs, scripts, parsers."""

from __future__ import annotations

import subprocess

from uavcas.emulation.apps import capture, client, images, nginx


def test_images_are_seeded_jpeg_sized(tmp_path):
    a = images.generate(tmp_path / "a", seed=3, count=12)
    b = images.generate(tmp_path / "b", seed=3, count=12)
    assert [(i.name, i.size_bytes) for i in a] == [(i.name, i.size_bytes) for i in b]
    assert (tmp_path / "a" / "img000.jpg").read_bytes() == (tmp_path / "b" / "img000.jpg").read_bytes()
    sizes = [i.size_bytes for i in a]
    assert all(20 * 1024 <= s <= 400 * 1024 for s in sizes) and max(sizes) > 2 * min(sizes)
    data = (tmp_path / "a" / "img003.jpg").read_bytes()
    assert data[:2] == b"\xff\xd8" and data[-2:] == b"\xff\xd9" and b"JFIF" in data[:20]
    assert len(data) == a[3].size_bytes
    assert images.image_sizes(4, 12) != images.image_sizes(3, 12)


def test_nginx_conf_has_no_systemd_defaults(tmp_path):
    site = nginx.NginxSite("uav0", "10.9.0.1", tmp_path / "img", tmp_path / "w")
    conf = nginx.render_conf(site)
    for needle in ("daemon off;", "user root;", f"pid {tmp_path / 'w' / 'nginx.pid'}", "listen 10.9.0.1:80",
                   "client_body_temp_path", f"root {tmp_path / 'img'}"):
        assert needle in conf
    assert "/var/" not in conf
    argv = nginx.argv(site)
    assert argv[:1] == ["nginx"] and "-e" in argv and str(site.conf_path) in argv


def test_client_assignment_and_script(tmp_path):
    assert client.assignments(["uav0", "uav1", "uav2"], ["bs0", "bs1"]) == [
        ("bs0", "uav0"), ("bs1", "uav1"), ("bs0", "uav2")]
    spec = client.ClientSpec("bs0", "uav2", "10.9.0.3", ("img000.jpg", "img001.jpg"), 12.0,
                             tmp_path / "log.tsv", seed=1)
    text = client.render_script(spec)
    assert text == client.render_script(spec)  # seeded
    assert "http://10.9.0.3:80/" in text and "--max-time" in text and "SECONDS + 12" in text
    path = client.write_script(spec, tmp_path / "c.sh")
    assert subprocess.run(["bash", "-n", str(path)]).returncode == 0


def test_client_log_parse():
    text = ("1700000000.5\t200\t1234\t0.05\timg001.jpg\n1700000001.0\t000\t0\t2.0\timg002.jpg\ngarbage\n"
            "1700000002.0\tskip\t0\t0\t3\n")
    f = client.parse_log(text)
    assert [x.ok for x in f] == [True, False] and f[0].size_bytes == 1234 and f[1].image == "img002.jpg"
    assert client.skipped_windows(text) == [3] and f[0].local_port is None  # a log from before the port
    now = client.parse_log("1700000000.5\t200\t1234\t0.05\t41234\timg001.jpg\n")
    assert now[0].local_port == 41234 and now[0].image == "img001.jpg" and now[0].size_bytes == 1234


def test_client_skips_the_windows_its_uav_is_disconnected(tmp_path):
    import time

    # nothing listens on 127.0.0.1:9: every fetch fails at once, so the loop runs freely; bash's
    # SECONDS ticks in whole seconds, so a 2 s budget lasts between 1 and 2 s: windows 0-3 always run
    t0 = time.time()
    spec = client.ClientSpec("bs0", "uav0", "127.0.0.1", ("a.jpg",), 2.0, tmp_path / "log.tsv", seed=1,
                             think_mean_s=0.02, port=9, t0_unix=t0, window_s=0.25, offline_windows=(1, 2))
    spec.log_path.write_text("")
    subprocess.run(["bash", str(client.write_script(spec, tmp_path / "c.sh"))], timeout=10, check=True)
    text = spec.log_path.read_text()
    assert client.skipped_windows(text) == [1, 2]  # one line per skipped window
    fetched = [int((f.t_unix - t0) // 0.25) for f in client.parse_log(text)]
    assert fetched and 0 in fetched and 3 in fetched and not {1, 2} & set(fetched)
    # curl's local_port is logged (a refused connect to 127.0.0.1:9 still bound a port)
    assert all(f.local_port is not None for f in client.parse_log(text))


def test_capture_stats_parse():
    err = ("tcpdump: listening on s0\n1234 packets captured\n1240 packets received by filter\n"
           "6 packets dropped by kernel\n")
    assert capture.parse_stats(err) == {"captured": 1234, "received by filter": 1240, "dropped by kernel": 6}
    argv = capture.argv("s3", capture.Path("/x/s-uav3.pcap"))
    assert "-p" not in argv and "-U" in argv and argv[argv.index("-Z") + 1] == "root"
    assert capture.point_name("uav3") == "s-uav3"


