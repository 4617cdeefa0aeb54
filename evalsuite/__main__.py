from evalsuite.cli import run

run()
