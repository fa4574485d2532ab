"""A test process trains a network once per set of inputs (`trained_once`, a fixture of the test files
that ask for it): gearlab.learn.training's fit_supervised and fit_adaptation, called again with the
same network, rows, generators and settings, give what the first call gave without training again.

The leak and protocol tests run a unit three times with only the target's test rows changed and
assert that the trainings do not change: the priming, the source model and many adaptations were
the same trainings each time, and again in the next test's variant (test_protocol, test_leak_labels
and test_detection: 11 s of the suite's 560 s of test CPU were such repeats). The memo's key is every
input a training reads, fingerprinted whole: the network (its classes, settings, weights, buffers and
modes), the arrays, the numpy generator's and torch's random states, every setting, the thread count.
A changed row, label or seed is another key, and trains. What the first call left is given back: the
network's weights, buffers, gradients and modes, the generators' states after it, the History, and
each on_epoch call with the History as it stood. An input it cannot fingerprint (a closure, an object
of unknown make) trains as usual. Tests that check training itself (test_training_*, the benchmarks)
do not ask for it; the fixture's own test holds that a memo's answer is the training's, bit for bit."""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import functools
import hashlib
import inspect
import os
import types
from collections.abc import Mapping

import numpy as np
import pytest
import torch

from gearlab.learn import training

MEMO: dict[str, dict] = {}  # key -> what the training left (remembered)
MOST = 512  # entries kept, oldest out first: the tiny networks' states are tens of kB each
ASKED = {"trained": 0, "given": 0}  # the process's trainings that ran, and those the memo answered
UNKEYED: list[str] = []  # why a training was not looked up


class Unkeyed(Exception):
    """An input the memo cannot fingerprint: the call trains as usual."""


def fingerprint(h, value, depth: int = 0) -> None:
    """Feed all of *value* that a training can read into the hash *h*; Unkeyed where that is not known."""
    if depth > 12:
        raise Unkeyed("nested too deep")
    up = h.update
    if value is None or isinstance(value, (bool, int, float, str, bytes, torch.device, torch.dtype)):
        up(f"{type(value).__name__}:{value!r};".encode())
    elif isinstance(value, np.ndarray):
        if value.dtype == object:
            raise Unkeyed("an object array")
        a = np.ascontiguousarray(value)
        up(f"nd{a.dtype}{a.shape};".encode())
        up(hashlib.sha1(a.view(np.uint8)).digest())
    elif isinstance(value, np.generic):
        up(f"{value.dtype}:{value!r};".encode())
    elif isinstance(value, torch.Tensor):
        up(f"t{value.dtype}{tuple(value.shape)}{value.device}{value.requires_grad};".encode())
        fingerprint(h, value.detach().cpu().contiguous().numpy(), depth + 1)
    elif isinstance(value, np.random.Generator):
        up(repr(value.bit_generator.state).encode())
    elif isinstance(value, torch.nn.Module):
        for name, module in value.named_modules():
            up(f"m{name}:{type(module).__module__}.{type(module).__qualname__}:{module.training};".encode())
            plain = {k: v for k, v in vars(module).items() if not k.startswith("_") and k != "training"}
            fingerprint(h, plain, depth + 1)
        for name, tensor in value.state_dict(keep_vars=True).items():
            up(name.encode())
            fingerprint(h, tensor, depth + 1)
    elif isinstance(value, types.MethodType):
        up(f"method {value.__func__.__module__}.{value.__func__.__qualname__};".encode())
        fingerprint(h, value.__self__, depth + 1)
    elif isinstance(value, types.FunctionType):
        if value.__closure__ or "<locals>" in value.__qualname__ or value.__name__ == "<lambda>":
            raise Unkeyed(f"function {value.__qualname__}")
        up(f"function {value.__module__}.{value.__qualname__};".encode())
    elif isinstance(value, Mapping):
        up(b"{")
        for k in sorted(value, key=repr):
            fingerprint(h, k, depth + 1)
            fingerprint(h, value[k], depth + 1)
        up(b"}")
    elif isinstance(value, (list, tuple)):
        up(f"{type(value).__name__}[".encode())
        for v in value:
            fingerprint(h, v, depth + 1)
        up(b"]")
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        up(f"dc {type(value).__module__}.{type(value).__qualname__};".encode())
        for f in dataclasses.fields(value):
            up(f.name.encode())
            fingerprint(h, getattr(value, f.name), depth + 1)
    elif type(value).__module__.startswith(("gearlab.", "gearlab_plugins.")) and not hasattr(value, "__slots__"):
        up(f"obj {type(value).__module__}.{type(value).__qualname__};".encode())
        fingerprint(h, vars(value), depth + 1)  # an adapter of the registry (plugins): its class and settings
    else:
        raise Unkeyed(f"a {type(value).__qualname__}")


def key_of(name: str, bound: inspect.BoundArguments, net: torch.nn.Module) -> str:
    h = hashlib.sha256(name.encode())
    h.update(f"threads {torch.get_num_threads()};".encode())
    fingerprint(h, torch.get_rng_state())
    for arg, value in bound.arguments.items():
        if arg == "on_epoch":
            continue  # replayed, not read by the training
        h.update(arg.encode())
        if arg == "parameters" and value is not None:  # which of the network's: by their names
            names = {id(p): n for n, p in net.named_parameters()}
            value = list(value)
            if any(id(p) not in names for p in value):
                raise Unkeyed("a parameter not of the network")
            value = [names[id(p)] for p in value]
        fingerprint(h, value)
    return h.hexdigest()


def _left(modules: list[torch.nn.Module]) -> list[dict]:
    """What a training leaves in each module: its tensors (values, gradients) and plain attributes."""
    out = []
    for module in modules:
        out.append(
            {
                "params": {n: (p.detach().clone(), None if p.grad is None else p.grad.clone())
                           for n, p in module.named_parameters()},
                "buffers": {n: b.clone() for n, b in module.named_buffers()},
                "modes": [m.training for m in module.modules()],
                "plain": [copy.deepcopy({k: v for k, v in vars(m).items() if not k.startswith("_")})
                          for m in module.modules()],
            }
        )  # fmt: skip
    return out


def _give_back(modules: list[torch.nn.Module], left: list[dict]) -> None:
    for module, state in zip(modules, left, strict=True):
        for n, p in module.named_parameters():
            value, grad = state["params"][n]
            p.data = value.clone()  # memory of its own, as the optimiser's release leaves it
            p.grad = None if grad is None else grad.clone()
        for n, b in module.named_buffers():
            b.copy_(state["buffers"][n])
        for m, plain in zip(module.modules(), state["plain"], strict=True):
            for k, v in plain.items():
                setattr(m, k, copy.deepcopy(v))
        for m, mode in zip(module.modules(), state["modes"], strict=True):
            m.training = mode


def _curves(history) -> tuple[list, ...]:
    return history.train_loss, history.val_acc, history.discrepancy, history.lam


def _replayed(final, epochs: list[tuple], on_epoch):
    """The History the training returned, built up as it was: every on_epoch call gets the one History
    object, its curves as long as they were then (they only grow), as the training hands it."""
    history = copy.deepcopy(final)
    if on_epoch is None:
        return history
    whole = [list(c) for c in _curves(history)]
    for epoch, *lengths, best, stopped in epochs:
        for curve, full, n in zip(_curves(history), whole, lengths[:4], strict=True):
            curve[:] = full[:n]
        history.best_epoch, history.stopped_epoch = best, stopped
        on_epoch(epoch, history)
    for curve, full in zip(_curves(history), whole, strict=True):
        curve[:] = full
    history.best_epoch, history.stopped_epoch = final.best_epoch, final.stopped_epoch
    return history


def remembered(real, name: str, owner: int):
    signature = inspect.signature(real)

    @functools.wraps(real)
    def memo(*args, **kwargs):
        if os.getpid() != owner:  # a pool's worker: trains as gearlab does
            return real(*args, **kwargs)
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        a = bound.arguments
        modules = [a["net"]] + ([a["modules"]] if "modules" in a else [])
        try:
            key = key_of(name, bound, a["net"])
        except Unkeyed as why:
            UNKEYED.append(str(why))
            return real(*args, **kwargs)
        on_epoch, rng = a.get("on_epoch"), a["rng"]
        if key in MEMO:
            got = MEMO[key]
            _give_back(modules, got["left"])
            rng.bit_generator.state = copy.deepcopy(got["rng"])
            torch.set_rng_state(got["torch_rng"].clone())
            ASKED["given"] += 1
            return _replayed(got["history"], got["epochs"], on_epoch)
        epochs = []  # each epoch's curve lengths, kept epoch and stop: for a later call's on_epoch

        def told(epoch, history):
            epochs.append((epoch, *map(len, _curves(history)), history.best_epoch, history.stopped_epoch))
            if on_epoch is not None:
                on_epoch(epoch, history)

        bound.arguments["on_epoch"] = told
        history = real(*bound.args, **bound.kwargs)
        ASKED["trained"] += 1
        if len(MEMO) >= MOST:
            MEMO.pop(next(iter(MEMO)))
        MEMO[key] = {
            "left": _left(modules),
            "rng": copy.deepcopy(rng.bit_generator.state),
            "torch_rng": torch.get_rng_state(),
            "epochs": epochs,
            "history": copy.deepcopy(history),
        }
        return history

    memo.real = real
    return memo


@contextlib.contextmanager
def trainings_remembered():
    """While open, this process's trainings of inputs already trained on are given back, not run again."""
    with pytest.MonkeyPatch.context() as mp:
        for name in ("fit_supervised", "fit_adaptation"):
            mp.setattr(training, name, remembered(getattr(training, name), name, os.getpid()))
        yield
