"""The `lbr` script's entry point: a Ctrl-C at any moment, even while Python is still importing the app, ends in
one line and exit 130 (``lbrcli.app.main`` handles it from then on)."""

from __future__ import annotations

import json
import signal
import sys


def run() -> None:
    """Import the app and run it; an interrupt during the import is reported like one during a command."""
    try:
        from .app import main
    except KeyboardInterrupt:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        sys.stderr.write("lbr: interrupted\n")
        if "--json" in sys.argv[1:]:
            sys.stdout.write(json.dumps({"ok": False, "exit_code": 130, "error": "interrupted"}) + "\n")
        sys.stdout.flush()
        sys.exit(130)
    main()
