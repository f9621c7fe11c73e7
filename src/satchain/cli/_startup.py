"""Imported first by the command line (:mod:`satchain.cli.main`): SIGTERM is answered from here on with one line and
exit status 143 (:func:`satchain._safety.install_startup_handler`), not only once a command has begun."""

from satchain._safety import install_startup_handler

install_startup_handler()
