"""Algorithm tests run single-threaded: small nets are faster that way and results repeat."""

import torch

torch.set_num_threads(1)
