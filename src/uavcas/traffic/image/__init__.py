"""The `image` app's code (`uavcas.traffic.apps.image` drives it): `images` (seeded JPEG-like
files, tens to hundreds of KB, served by every UAV), `nginx` (one per UAV: own conf, `daemon
off`, paths under the run dir), `client` (one curl loop per UAV on its base station)."""
