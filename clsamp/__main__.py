"""``python -m clsamp`` and the ``clsamp`` console script: the command line
(:func:`clsamp.cli.main`), then the end of the process."""

import os
import sys

from .cli import main


def entry(argv=None):
    """Run the command line and end the process with its exit status: the ``clsamp``
    console script and ``python -m clsamp``.

    A command stopped by Ctrl-C or SIGTERM (status 130 or 143) ends at once, without the
    interpreter's teardown: its outputs are already whole or removed
    (:func:`clsamp.cli.main`), while device work it had queued may still be running, and
    the teardown around that work has aborted the process (SIGABRT, a fatal error in an
    extension) instead of ending it with the command's status.

    Parameters
    ----------
    argv : list of str, optional
        As for :func:`clsamp.cli.main`.
    """
    status = main(argv)
    if status in (130, 143):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):     # a closed pipe: nothing more can be said
                pass
        os._exit(status)
    else:
        sys.exit(status)


if __name__ == "__main__":
    entry()
