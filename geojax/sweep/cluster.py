"""Sweeps beyond one machine: each chunk a Ray task on a worker that compiled once (docs/design.md, "Scale").

``geojax sweep SWEEP.toml --out FILE.h5 --ray [ADDRESS]`` (``sweep.run_sweep(..., ray=ADDRESS)``) plans the
chunks exactly as a local sweep does and hands them to Ray.  The workers are Ray actors, by default one
per GPU of a GPU node and one per CPU node, each using its share of the node's cores (or its GPU) as XLA
devices through ``parallel.per_device``; a
worker compiles each controller once (``sweep.ChunkRunner``) and runs chunk after chunk.  The driver
keeps at most two chunks queued per worker, so a fast worker takes more, and writes every finished chunk
into ``FILE.h5.parts/`` itself, atomically and once: ``--resume`` continues whatever stopped (the driver,
a worker, a node), with or without Ray.

Failures: a worker whose process dies is restarted by Ray and its queued chunks retried
(``MAX_RESTARTS``, ``max_task_retries``); a worker that cannot be restarted is dropped and its chunks go
to the others; a chunk that has failed ``MAX_ATTEMPTS`` times, or the last worker lost, stops the sweep
with the chunks done saved.  An error raised by the engine inside a worker (a bad scenario value) is
raised here as itself.

Same numbers: a sample's keys come from (seed, global index) and every worker compiles one-device programs
whose numbers do not depend on their width (``geojax.lanes``: the platform's, or the sweep's ``lanes``),
so the file is bit for bit a local run's on the same platform, whatever the number of workers, their device
counts and the order chunks finish in.
"""

from __future__ import annotations

import collections
import contextlib
import os
import socket
import warnings

MAX_RESTARTS = 3  # per worker, before it is dropped
MAX_ATTEMPTS = 4  # per chunk, across workers
QUEUED_PER_WORKER = 2  # chunks sent ahead to each worker: one running, one waiting
CONNECT_TIMEOUT_S = 5.0


class ClusterError(RuntimeError):
    """The cluster could not finish the sweep (every worker lost, a chunk failing everywhere); the chunks
    done are saved and ``resume=True`` (``--resume``) continues."""


@contextlib.contextmanager
def connected(address: str):
    """Join (``"auto"``, ``"HOST:PORT"``, ``"ray://HOST:PORT"``) or start (``"local"``: always a new instance of
    its own, on 127.0.0.1, whatever clusters Ray has recorded) a Ray instance for the duration of the block;
    ``ValueError`` in one line, within seconds, if Ray is missing or the cluster unreachable (nothing listening
    at its address: a cluster killed leaves its address recorded).

    If this process has already joined one (``ray.init`` in a notebook or a test), that one is used.
    """
    try:
        import ray
    except ImportError:
        raise ValueError('ray: Ray is not installed; pip install "geojax[ray]"') from None
    if ray.is_initialized():
        yield ray
        return
    if address == "auto":
        _check_reachable(_recorded_cluster(address), named=address)
    elif address != "local":
        _check_reachable(address)
    try:
        with warnings.catch_warnings():  # Ray starts its processes by fork and exec, which JAX's warning
            warnings.filterwarnings("ignore", "os.fork", RuntimeWarning)  # about forking threads does not concern
            if address == "local":
                # An instance of our own, on the loopback address: ``ray.init()`` without an address would join
                # the cluster recorded in Ray's temporary folder, and wait ten minutes on one that was killed.
                ray.init(address="local", _node_ip_address="127.0.0.1", include_dashboard=False,
                         logging_level="ERROR")
            else:
                ray.init(address=address, logging_level="ERROR")
    except (ConnectionError, RuntimeError, ValueError, TimeoutError) as err:
        first = (str(err).strip().splitlines() or [type(err).__name__])[0]
        hint = "; start one with `ray start --head`" if address == "auto" else ""
        raise ValueError(f"ray={address}: {first}{hint}") from None
    try:
        yield ray
    finally:
        ray.shutdown()


def _recorded_cluster(address: str) -> str:
    """The HOST:PORT that ``"auto"`` means: ``RAY_ADDRESS``, else the cluster the last ``ray start`` on this
    machine recorded (Ray's own lookup); ``ValueError`` in one line where there is none."""
    from ray._private.services import canonicalize_bootstrap_address

    try:
        found = canonicalize_bootstrap_address(address)
    except (ConnectionError, ValueError) as err:
        found, why = None, f" ({(str(err).strip().splitlines() or [''])[0]})"
    else:
        why = ""
    if not found:
        raise ValueError(f"ray={address}: no running Ray cluster found on this machine{why}; start one with "
                         f"`ray start --head`, or give --ray alone for an instance of this sweep's own")
    return found


def _check_reachable(address: str, named: str | None = None) -> None:
    """Fail fast, in one line, where nothing listens at ``address`` (Ray itself retries for 20-30 s, or ten
    minutes on a cluster it finds recorded); the message names ``named`` (default ``address``), what was given."""
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"ray={address}: expected local, auto, HOST:PORT or ray://HOST:PORT")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as err:
        raise ValueError(f"ray={named or address}: cannot reach {host}:{port} ({err.strerror or err})") from None


class ChunkWorker:
    """A Ray actor: one worker process, its XLA devices, each controller compiled once (for ``chunk``
    samples a call at most) by ``make_runner(sweep, controller, chunk)`` (the sweep's ``ChunkRunner``: an object
    with ``compile_s`` and ``run(first, length)``), which the sweep hands over, so this module imports nothing
    of the sweep."""

    def __init__(self, sweep, devices: int, chunk: int, make_runner):
        from geojax.parallel import use_host_cores

        use_host_cores(devices, replace=True)  # before this process's first JAX computation
        self.sweep, self.chunk, self.make_runner, self.runners = sweep, chunk, make_runner, {}

    def run(self, controller: str, first: int, length: int):
        """The metrics of one chunk, and (process id, seconds compiling for it)."""
        compile_s = 0.0
        if controller not in self.runners:
            self.runners[controller] = self.make_runner(self.sweep, controller, self.chunk)
            compile_s = self.runners[controller].compile_s
        return self.runners[controller].run(first, length), (os.getpid(), compile_s)


def placements(nodes: list[dict], workers: int | None) -> list[tuple[str, int, float]]:
    """(node id, XLA CPU devices, GPUs) of each worker.

    By default one worker per GPU of a GPU node (``num_gpus = 1``: Ray makes that GPU the worker's only JAX
    device, so each runs the one-device program at the GPU's width) and one per CPU node, the node's cores
    shared by its workers.  ``workers``: that many, round-robin over the alive nodes (ordered by id), each an
    equal share of its node's CPUs and GPUs (Ray hides the GPUs from a worker that does not ask for them).
    """
    alive = sorted((n for n in nodes if n.get("Alive") and n.get("Resources", {}).get("CPU", 0) >= 1),
                   key=lambda n: n["NodeID"])
    if not alive:
        raise ValueError("ray: the cluster has no alive node with a CPU")
    if workers is None:
        placed = []
        for node in alive:
            cpus, gpus = int(node["Resources"]["CPU"]), int(node["Resources"].get("GPU", 0.0))
            placed += [(node["NodeID"], max(1, cpus // max(1, gpus)), 1.0 if gpus else 0.0)] * max(1, gpus)
        return placed
    per_node = collections.Counter(i % len(alive) for i in range(workers))
    placed = []
    for i in range(workers):
        node, sharing = alive[i % len(alive)], per_node[i % len(alive)]
        gpus = node["Resources"].get("GPU", 0.0)
        placed.append((node["NodeID"], max(1, int(node["Resources"]["CPU"]) // sharing),
                       float(gpus // sharing if gpus >= sharing else gpus / sharing)))
    return placed


def default_chunk(n_samples: int, nodes: list[dict]) -> int | None:
    """Samples per chunk on a cluster with GPUs: an even share of the sweep per GPU worker, at most one GPU
    batch (``lanes.ACCELERATOR_MAX_LANES``), so every GPU gets work and each call is wide; ``None`` on a
    cluster of CPUs (the driver's own width then serves, as every CPU worker computes the same).  The
    workers size their batch to their GPU's memory themselves.  ``nodes``: ``ray.nodes()``."""
    import math

    from geojax.lanes import ACCELERATOR_MAX_LANES

    gpus = sum(int(n.get("Resources", {}).get("GPU", 0)) for n in nodes if n.get("Alive"))
    return max(1, min(math.ceil(n_samples / gpus), ACCELERATOR_MAX_LANES)) if gpus else None


def run_chunks(sweep, todo: list[tuple[str, int, int]], save, bar, workers: int | None = None, *,
               make_runner) -> float:
    """Run each (controller, first sample, length) of ``todo`` on the cluster joined by ``connected``, each
    worker computing its chunks with the runners ``make_runner`` builds (``ChunkWorker``), calling
    ``save(controller, first, values)`` once per chunk as it finishes.  Returns the longest compilation of any
    worker (seconds)."""
    import ray
    from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

    if not todo:
        return 0.0
    remote = ray.remote(ChunkWorker)
    actors = [remote.options(num_cpus=devices, num_gpus=gpus, max_restarts=MAX_RESTARTS,
                             max_task_retries=MAX_RESTARTS,
                             scheduling_strategy=NodeAffinitySchedulingStrategy(node, soft=True))
              .remote(sweep, devices, max(length for _, _, length in todo), make_runner)
              for node, devices, gpus in placements(ray.nodes(), workers)]
    live = set(range(len(actors)))
    pending = collections.deque(todo)
    inflight: dict = {}  # ObjectRef -> (worker, chunk)
    attempts = collections.Counter()
    pids = collections.defaultdict(set)  # worker -> the processes it has run in (a restart adds one)
    compile_s = 0.0

    def note():
        restarts = sum(len(p) - 1 for p in pids.values() if p)
        bar.note = f"{len(live)}/{len(actors)} workers alive" + (f", {restarts} restarted" if restarts else "")
        bar.update(0)

    try:
        note()
        while pending or inflight:
            if not live:
                raise ClusterError("every Ray worker was lost; the chunks done are saved: resume=True continues")
            for w in sorted(live):
                while pending and sum(1 for v, _ in inflight.values() if v == w) < QUEUED_PER_WORKER:
                    task = pending.popleft()
                    inflight[actors[w].run.remote(*task)] = (w, task)
            ready, _ = ray.wait(list(inflight), num_returns=1, timeout=1.0)
            for ref in ready:
                w, task = inflight.pop(ref)
                try:
                    values, (pid, seconds) = ray.get(ref)
                except ray.exceptions.RayTaskError as err:  # the engine raised: the same error here
                    raise (err.cause if isinstance(err.cause, Exception) else err) from None
                except ray.exceptions.RayError as err:  # the worker is gone for good: its chunks go elsewhere
                    attempts[task] += 1
                    if attempts[task] >= MAX_ATTEMPTS:
                        raise ClusterError(f"chunk {task[0]} from sample {task[1]} failed {attempts[task]} times; "
                                           f"last: {str(err).splitlines()[0]}; resume=True continues") from None
                    live.discard(w)
                    pending.appendleft(task)
                    note()
                    continue
                save(*task[:2], values)
                pids[w].add(pid)
                bar.update(task[2])
                if seconds > compile_s:  # a worker's first chunk of a controller: the rate starts after it
                    compile_s = seconds
                    bar.restart()
                note()
        return compile_s
    finally:
        for actor in actors:
            ray.kill(actor)
