"""crux.World: one question put to crux or to a peer library, over crux's batch protocol.

A World runs ``crux batch --backend <backend>`` (the JSON Lines protocol of docs/batch.md) as a
child process and exchanges one JSON line per request, so a Python user can cross-check an
answer of crux's native kernel against the exact CGAL kernel and the peers (FCL, Bullet).
"""

import json
import os
import shutil
import subprocess
import tempfile
import threading

import numpy as np

BACKENDS = ("native", "exact", "fcl", "bullet")


class WorldError(RuntimeError):
    """The batch process could not be started or stopped answering."""


def _executable(explicit):
    if explicit:
        return explicit
    if os.environ.get("CRUX_EXECUTABLE"):
        return os.environ["CRUX_EXECUTABLE"]
    try:
        from ._build import CRUX_EXECUTABLE
    except ImportError:
        CRUX_EXECUTABLE = ""
    if CRUX_EXECUTABLE and os.path.exists(CRUX_EXECUTABLE):
        return CRUX_EXECUTABLE
    found = shutil.which("crux")
    if not found:
        raise WorldError("the crux command line was not found: set CRUX_EXECUTABLE or put crux on PATH")
    return found


def _jsonable(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    return value


class World:
    """A collision world of one backend ("native", "exact", "fcl" or "bullet") behind the batch
    protocol. ``request(op, **fields)`` sends one request and returns the answer as a dict; an
    answer with "error" raises ValueError (its message is crux's) or, for an op the backend cannot
    answer, NotImplementedError("unsupported: <op> on <backend>"). Use as a context manager, or
    call close()."""

    def __init__(self, backend="native", executable=None):
        if backend not in BACKENDS:
            raise ValueError("backend: expected one of %s, got %r" % (", ".join(BACKENDS), backend))
        self.backend = backend
        self._stderr = tempfile.TemporaryFile()
        self._lock = threading.Lock()
        self._proc = subprocess.Popen(
            [_executable(executable), "batch", "--backend", backend],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            text=True,
            bufsize=1,
        )
        self._next = 0

    def _failure(self):
        self._stderr.seek(0)
        message = self._stderr.read().decode(errors="replace").strip()
        return WorldError("crux batch --backend %s stopped: %s" % (self.backend, message or "no message"))

    def requests(self, requests):
        """Sends many requests (dicts with "op") and returns their answers, in order. Error answers
        are returned as they are (with an "error" member), not raised."""
        lines = [json.dumps(_jsonable(r), allow_nan=False) + "\n" for r in requests]
        with self._lock:
            if self._proc.poll() is not None:
                raise self._failure()
            writer = threading.Thread(target=self._write, args=(lines,))
            writer.start()
            answers = []
            for _ in lines:
                line = self._proc.stdout.readline()
                if not line:
                    break
                answers.append(json.loads(line))
            writer.join()
            if len(answers) != len(lines):
                raise self._failure()
            return answers

    def _write(self, lines):
        try:
            for line in lines:
                self._proc.stdin.write(line)
            self._proc.stdin.flush()
        except (BrokenPipeError, ValueError):
            pass  # the reader reports the failure

    def request(self, op, **fields):
        """Sends one request and returns its answer (a dict without "id"/"op")."""
        self._next += 1
        req = {"id": str(self._next), "op": op}
        req.update(fields)
        answer = self.requests([req])[0]
        error = answer.get("error")
        if error is not None:
            if error.startswith("unsupported:"):
                raise NotImplementedError(error)
            raise ValueError(error)
        answer.pop("id", None)
        answer.pop("op", None)
        return answer

    def add_mesh(self, name, mesh):
        """Defines mesh `name` in the world from a crux.Mesh (its vertices, exactly, and triangles)."""
        return self.request(
            "mesh", name=name, vertices=mesh.vertices.astype(np.float64), triangles=mesh.triangles.astype(np.int64)
        )

    def close(self):
        """Ends the batch process."""
        if self._proc.poll() is None:
            try:
                self._proc.stdin.close()
            except OSError:
                pass
            try:
                self._proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        self._proc.stdout.close()
        self._stderr.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        proc = getattr(self, "_proc", None)
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()
