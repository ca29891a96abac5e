from gadgetctl.cli.main import main

main()
