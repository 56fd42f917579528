"""The built-site checks (test_site.py) belong to ``make docs``, which builds the site and then
runs them with ``PALAESTRA_DOCS_BUILT=1``; the default suite has no site to read, so it leaves
them out instead of reporting them skipped."""

import os

collect_ignore = [] if os.environ.get("PALAESTRA_DOCS_BUILT") == "1" else ["test_site.py"]
