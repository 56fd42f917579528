"""Exceptions raised by palaestra.

The hierarchy and names follow Gymnasium 1.x so that code catching ``gymnasium.error.X`` keeps
working with ``palaestra.error.X``.
"""

from __future__ import annotations


class Error(Exception):
    """Base class of palaestra's errors."""


# Registration
class UnregisteredEnv(Error):
    """An environment id that is not in the registry was requested."""


class NamespaceNotFound(UnregisteredEnv):
    """The namespace of the requested id does not exist."""


class NameNotFound(UnregisteredEnv):
    """The name of the requested id does not exist (in its namespace)."""


class VersionNotFound(UnregisteredEnv):
    """The version of the requested id does not exist."""


class InvalidEnvId(Error, ValueError):
    """An id that is not ``[module:][namespace/]Name[-vN]``: more than one ``:``, or nothing
    before it. Also a ``ValueError``, which is what Gymnasium's ``make`` raises for these."""


class DeprecatedEnv(Error):
    """An older version than the latest registered one was requested."""


class RegistrationError(Error):
    """An invalid registration, e.g. an unversioned id next to versioned ones."""


# Environment
class DependencyNotInstalled(Error):
    """An optional dependency is missing; the message names the ``pip install`` that fixes it."""


class UnsupportedMode(Error):
    """A render mode the environment does not support was requested."""


class InvalidModelFile(Error, ValueError):
    """A model file (a MuJoCo env's ``xml_file``) that does not compile; the message names the
    path and the simulator's own message."""


class InvalidMetadata(Error):
    """The environment's ``metadata`` is malformed."""


class ResetNeeded(Error):
    """``step`` or ``render`` was called before ``reset``."""


class InvalidAction(Error, ValueError):
    """An action outside the action space was given.

    Also a ``ValueError``: Gymnasium's vector envs raise ValueError for a batch of the wrong
    size, and code written for them catches that.
    """


class InvalidOptions(Error, TypeError):
    """Reset options that are neither ``None`` nor a dict (or, for ``VecEnv.set_options``, one
    dict per env). Also a ``TypeError``: what Gymnasium's envs and SB3's ``VecEnv.reset`` raise
    for such options when they fail at all."""


class OptionsCountError(Error, ValueError, IndexError):
    """``VecEnv.set_options`` got a list with one entry per env, but not ``num_envs`` of them.
    A ``ValueError``; also an ``IndexError``, which is what SB3's ``reset`` raises then."""


class MissingArgument(Error):
    """A required constructor argument is missing."""


class InvalidProbability(Error):
    """A probability mask is not a valid distribution."""


class InvalidBound(Error):
    """Clipping bounds are invalid (e.g. ``low > high``)."""


# Wrappers
class DeprecatedWrapper(ImportError):
    """An old wrapper name was imported."""


# Vector environments
class AlreadyPendingCallError(Exception):
    """An async call was started while the previous one is still pending."""

    def __init__(self, message: str, name: str) -> None:
        super().__init__(message)
        self.name = name


class NoAsyncCallError(Exception):
    """``*_wait`` was called with no matching ``*_async`` call pending."""

    def __init__(self, message: str, name: str) -> None:
        super().__init__(message)
        self.name = name


class ClosedEnvironmentError(Exception):
    """The vector environment was used after ``close()``."""


class CustomSpaceError(Exception):
    """A custom space cannot be placed in shared memory."""


class DynamicShapeSpaceError(CustomSpaceError, TypeError):
    """A space of dynamic shape (Graph, Sequence) cannot be placed in static shared memory.

    Also a ``TypeError``, which is what Gymnasium's ``create_shared_memory`` raises for them.
    """


class SharedMemoryError(CustomSpaceError, ValueError):
    """``AsyncVectorEnv(shared_memory=True)`` cannot hold the observation space.

    Also a ``ValueError``, which is what Gymnasium's ``AsyncVectorEnv`` raises (callers catch it
    to retry with ``shared_memory=False``).
    """


def dependency_not_installed(package: str, extra: str, purpose: str) -> DependencyNotInstalled:
    """Build the standard error for a missing optional dependency.

    >>> str(dependency_not_installed("torch", "train", "training agents"))
    'torch is not installed, run `pip install "palaestra[train]"` (needed for training agents)'
    """
    return DependencyNotInstalled(
        f'{package} is not installed, run `pip install "palaestra[{extra}]"` (needed for {purpose})'
    )


# Algorithms
class UnsupportedSpace(Error, TypeError):
    """An algorithm was given an observation or action space it cannot learn on (a TypeError,
    as palaestra has always raised it)."""


class InvalidObservation(Error, ValueError, AssertionError):
    """An observation (or an env's observation space) that does not fit the model's or the
    wrapper's. A ``ValueError``; also an ``AssertionError``, which is what SB3 raises in the same
    places (``predict`` of a dict on a non-Dict space, ``VecNormalize.set_venv``)."""


class NotAVecEnv(Error, TypeError, AttributeError):
    """Something that is not a ``palaestra.vec_env.VecEnv`` where one is needed. A
    ``TypeError``; also an ``AttributeError``, which is what SB3's ``VecNormalize.set_venv``
    raises (reading ``venv.num_envs``)."""


class VecEnvAlreadySet(Error, ValueError):
    """``VecNormalize.set_venv`` on a wrapper that already wraps a vector env (a
    ``ValueError``, as in SB3)."""


class InvalidEnvFunction(Error, TypeError):
    """A vector env's ``env_fns`` entry that is not callable (often an env instead of a
    function making one). A ``TypeError``, as Gymnasium and SB3 raise calling it."""


class InvalidNumEnvs(Error, ValueError, TypeError, IndexError):
    """``n_envs`` that is not an int >= 1. A ``ValueError``; also what SB3's ``make_vec_env``
    raises for such values by accident: ``TypeError`` (not an int), ``IndexError`` (< 1)."""


class InvalidCallback(Error, TypeError):
    """A ``callback`` argument that is not a callback instance, a function or a list of them
    (e.g. the class itself). Also a ``TypeError``, which is what SB3 raises for these."""


# Run state (exact resume)
class RunStateError(Error, ValueError):
    """A run state cannot be saved by, or does not fit, the object it is restored into."""
