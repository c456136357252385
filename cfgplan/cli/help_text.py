"""The top-level help of ``cfgplan`` (``--help``, ``-h``, and bare ``cfgplan``)
as typer renders it at 80 columns, printed without loading typer.

Generated from the typer app by ``python -m cfgplan.cli.root``: do not edit;
tests/cli/test_startup.py fails when it drifts from the app.
"""

WIDTH = 80
HELP = (
    "Usage: cfgplan [OPTIONS] COMMAND [ARGS]...\n"
    "\n"
    "  Plan-based configuration of robot societies (R. Lundh, 2006).\n"
    "\n"
    "Options:\n"
    "  --version             Print cfgplan's version and exit.\n"
    "  --install-completion  Install completion for the current shell.\n"
    "  --show-completion     Show completion for the current shell, to copy it or\n"
    "                        customize the installation.\n"
    "  -h, --help            Show this message and exit.\n"
    "\n"
    "Commands:\n"
    "  check     Check a domain (and a state with its goal) without planning.\n"
    "  emit      Write one executable file per robot for a configuration (5.1-5.3).\n"
    "  keys      Make or renew a society's keys for TLS with mutual authentication.\n"
    "  launch    Start a whole society here, one process per robot (5.2.2).\n"
    "  plan      Plan ranked admissible configurations (4.5), or sequences of them.\n"
    "  record    Turn a run's trace into an MCAP file that Foxglove opens.\n"
    "  render    Draw a configuration (Fig. 4.3) or a method hierarchy (Fig. 4.4).\n"
    "  report    Draw any run (a trace or an MCAP recording): pictures and a page.\n"
    "  router    Run a Zenoh router for robots started with --router.\n"
    "  run       Run a configuration: all robots here, or one on the network (5.2).\n"
    "  simulate  Run a thesis experiment in the 2-D simulator (chapter 6).\n"
)
