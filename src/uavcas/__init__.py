"""uavcas: a calibrated digital twin of UAV swarm networks on real Linux stacks, its attacks, and
the labeled intrusion-detection datasets made from what crosses the wire."""

__version__ = "0.1.0"


def __getattr__(name: str):
    # lazy: `import uavcas` stays light (no pandas) for the CLI and the emulation
    if name == "load_dataset":
        from uavcas.dataset.load import load_dataset  # on first use of uavcas.load_dataset (pandas)

        return load_dataset
    raise AttributeError(f"module 'uavcas' has no attribute {name!r}")


__all__ = ["__version__", "load_dataset"]
