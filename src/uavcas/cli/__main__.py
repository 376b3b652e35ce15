from uavcas.cli import main

main()
