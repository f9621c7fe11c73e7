"""``python -m satchain ...``: the same command line as the ``satchain`` script."""

from satchain.cli import app

if __name__ == "__main__":
    app(prog_name="satchain")
