# SPDX-License-Identifier: Apache-2.0
"""Panoptes motion tracking for Python: bodies, markers and latency from the estimator.

    import panoptes
    with panoptes.Client() as client:            # loopback profile, $PANOPTES_DOMAIN
        frame = client.wait_for_frame(2.0)       # None on timeout: client.status_text() says why
        head = frame.body("head")
        print(head.position, head.orientation)   # NumPy float64 arrays, (3,) and (4,) x y z w

Push instead of pull: ``client.add_callback(fn)`` calls ``fn(frame)`` on the library's receive
thread. The C++ API is the same (panoptes/client/client.h); docs/clients.md has the guide.
"""
import numpy  # noqa: F401  (imported now rather than at the first frame's first array)

from panoptes._panoptes import (
    BodyDescription,
    CameraHealth,
    Client,
    ClientError,
    EstimatorHealth,
    Frame,
    Latency,
    Marker,
    RigidBody,
    Stats,
    UnknownBody,
    version,
    version_info,
)

__version__ = version()  # the client library's version ("0.1.0"); version_info: (0, 1, 0)

__all__ = [
    "BodyDescription",
    "CameraHealth",
    "Client",
    "ClientError",
    "EstimatorHealth",
    "Frame",
    "Latency",
    "Marker",
    "RigidBody",
    "Stats",
    "UnknownBody",
    "frames",
    "version",
    "version_info",
]


def frames(client, timeout):
    """Yields frames from ``client.wait_for_frame(timeout)`` until one does not come in time or the
    client is closed; then ``client.status_text()`` says which."""
    while True:
        frame = client.wait_for_frame(timeout)
        if frame is None:
            return
        yield frame
