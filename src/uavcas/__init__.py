"""uavcas: a calibrated digital twin of UAV swarm networks on real Linux stacks, its attacks, and
the labeled intrusion-detection datasets made from what crosses the wire."""

__version__ = "0.1.0"
