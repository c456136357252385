"""``python -m cfgplan``: the same as the ``cfgplan`` command."""

from cfgplan.cli.app import console

if __name__ == "__main__":
    console()
