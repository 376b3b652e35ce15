"""Real programs run inside an emulation's namespaces: benign traffic, capture.
(The attack tools live beside their families, `uavcas.attacks.tools`; the fabric-side rules of
attacks, e.g. the blackhole's nft table, in the families' modules.)

* `images`    seeded JPEG-like payloads (tens to hundreds of KB) served by every UAV;
* `nginx`     one nginx per UAV (no systemd: own conf, `daemon off`, paths under the run dir);
* `client`    one curl loop per UAV on its base station (UAV i is fetched by BS i mod n_bs);
* `mavlink`   MAVLink v2 (pymavlink): an autopilot per UAV, a ground station per BS on UDP 14550
              (payload telemetry, video or mixed): streams, mission upload, per-window commands;
* `video`     H.264 over RTP/UDP per UAV (ffmpeg, seeded test pattern, constant bitrate) to a
              byte-counting sink on its BS, port 5600 (payload video or mixed);
* `capture`   one tcpdump per switch, with its drop counters;
* `traffic`   the benign traffic of a run by the scenario's payload (servers before t0, clients at t0);
* `procs`     a supervised process: started in its own session, stopped by PID with a signal;
* `versions`  versions of the external tools, for run.json.
"""
