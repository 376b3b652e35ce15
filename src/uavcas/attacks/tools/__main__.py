"""`python -m uavcas.attacks.tools TOOL ARGS`: run one attack tool's process (its `main(ARGS)`).

TOOL: `pacer` (the flood's: `pacer --pid P --pps R`, which the flood starts by its file's path),
`replayer` or `mavinject`; bad input ends in one line on stderr and exit status 2.
"""

from __future__ import annotations

import sys
from collections.abc import Callable

from . import mavinject, pacer, replayer

TOOLS: dict[str, Callable[[list[str]], int | None]] = {
    "mavinject": mavinject.main,
    "pacer": pacer.main,
    "replayer": replayer.main,
}


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if not args or args[0] not in TOOLS:
        print(f"usage: python -m uavcas.attacks.tools {{{','.join(TOOLS)}}} ARGS", file=sys.stderr)
        return 2
    return TOOLS[args[0]](args[1:]) or 0


if __name__ == "__main__":
    sys.exit(main())
