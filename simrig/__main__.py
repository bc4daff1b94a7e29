"""``python -m simrig``: the ``simrig`` command (for an environment whose scripts folder is not on the PATH)."""

from simrig.cli import console

if __name__ == "__main__":
    console()
