"""python -m uavcas: the `uavcas` command."""

from uavcas.cli import main

main()
