"""Benign traffic: the traffic apps a run's payload is composed of.

* `payloads`  the one table of payloads (name -> its apps, in start order): read by the scenario
              codec, `Scenario.payload` and the data dictionary (imports nothing of uavcas);
* `base`      what an app is (`TrafficApp`: start its servers before t0, its clients at t0, its
              processes to stop, its section of run.json) and its context (`AppContext`);
* `registry`  app name -> class; `apps` imports every app module (`image`, `mavlink`, `video`)
              and derives `MAVLINK_PAYLOADS` from the apps' `carries_mavlink`;
* `benign`    `BenignTraffic`: a run's payload, its apps driven in the row's order;
* the apps' own code: `image` (nginx, curl clients, seeded images), `mavlink` (the endpoints,
  run as `python -m uavcas.traffic.mavlink`), `video` (ffmpeg sender, `python -m
  uavcas.traffic.video sink`).

This `__init__` loads nothing: the endpoints' processes import their own subpackage only, and the
scenario's records read `payloads` without loading an app.
"""
