"""network: the model of the emulated network that the offline stages share with the emulator.

Pure (no subprocess, no kernel, no root): the frame size and queue limits a switch port holds
(`queues`), the L2 forwarding of a window (`forwarding`: the static tables per destination and
the wormhole detours) and the names of a run's nodes, ports and namespaces (`naming`). The
emulator (`uavcas.emulation`) applies them to the kernel; the packet follower and the copy
matcher (`uavcas.flows`) and the fidelity audit (`uavcas.fidelity`) model a run with them, so
those stages never import the kernel package.
"""
