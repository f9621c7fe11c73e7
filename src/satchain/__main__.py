"""``python -m satchain ...``: the same command line as the ``satchain`` script."""

from satchain.cli.main import app

if __name__ == "__main__":
    app(prog_name="satchain")
