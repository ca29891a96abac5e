from gadgetctl.cli.main import run

run()
