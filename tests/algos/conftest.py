"""Algorithm tests run single-threaded: small nets are faster that way and results repeat."""

import torch

torch.set_num_threads(1)

# data/ holds fixtures and the scripts that wrote them with older code (they import modules
# that have since moved): data, not tests or doctests.
collect_ignore_glob = ["data/*"]
