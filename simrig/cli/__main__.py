"""``python -m simrig.cli``: the ``simrig`` command (as ``python -m simrig``)."""

from simrig.cli import console

if __name__ == "__main__":
    console()
