"""Built-in environments, registered under Gymnasium's ids."""

from palaestra.envs.registration import make, pprint_registry, register, registry, spec

__all__ = ["make", "pprint_registry", "register", "registry", "spec"]
