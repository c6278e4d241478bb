"""Shared fixtures of the gwnrt Python tests: the data directory (GWNRT_DATA_DIR) and small
analytic meshes built in numpy, each a (vertices float64 (n, 3), faces int64 (m, 3)) pair with
counter-clockwise faces seen from outside."""

import os

import numpy as np
import pytest

import gwnrt


class Mesh:
    """Vertices and faces, as an object with .vertices and .faces."""

    def __init__(self, vertices, faces):
        self.vertices = np.asarray(vertices, dtype=np.float64)
        self.faces = np.asarray(faces, dtype=np.int64)

    def __iter__(self):  # vertices, faces = mesh
        return iter((self.vertices, self.faces))


def tetrahedron_mesh():
    v = [[0.1, -0.2, 0.0], [1.3, 0.1, -0.1], [0.2, 1.1, 0.2], [0.3, 0.2, 1.2]]
    f = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]
    return Mesh(v, f)


def octahedron_mesh():
    v = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
    f = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return Mesh(v, f)


def cube_faces():
    # Two triangles per side of the cube [-1, 1]^3 (corner i at (+-1, +-1, +-1) by its bits x, y, z),
    # the top (+z) side last.
    return [
        [0, 2, 3], [0, 3, 1],  # -z
        [0, 1, 5], [0, 5, 4],  # -y
        [2, 6, 7], [2, 7, 3],  # +y
        [0, 4, 6], [0, 6, 2],  # -x
        [1, 3, 7], [1, 7, 5],  # +x
        [4, 5, 7], [4, 7, 6],  # +z
    ]


def cube_vertices():
    return [[2.0 * (i & 1) - 1, 2.0 * ((i >> 1) & 1) - 1, 2.0 * ((i >> 2) & 1) - 1] for i in range(8)]


def cube_mesh():
    return Mesh(cube_vertices(), cube_faces())


def open_cube_mesh():
    """The cube without its top (+z) side: a square hole at z = 1."""
    return Mesh(cube_vertices(), cube_faces()[:-2])


def soup_mesh(count=40, seed=7):
    """`count` unconnected random triangles in [-1, 1]^3."""
    rng = np.random.default_rng(seed)
    return Mesh(rng.uniform(-1, 1, (3 * count, 3)), np.arange(3 * count).reshape(count, 3))


@pytest.fixture(scope="session")
def data_dir():
    path = os.environ.get("GWNRT_DATA_DIR",
                          os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "data"))
    if not os.path.isdir(path):
        pytest.skip(f"GWNRT_DATA_DIR ({path}) is not a directory")
    return path


@pytest.fixture(scope="session")
def tetrahedron():
    return tetrahedron_mesh()


@pytest.fixture(scope="session")
def octahedron():
    return octahedron_mesh()


@pytest.fixture(scope="session")
def cube():
    return cube_mesh()


@pytest.fixture(scope="session")
def open_cube():
    return open_cube_mesh()


@pytest.fixture(scope="session")
def soup():
    return soup_mesh()


@pytest.fixture(scope="session", params=["tetrahedron", "octahedron", "cube"])
def closed_mesh(request):
    builders = {"tetrahedron": tetrahedron_mesh, "octahedron": octahedron_mesh, "cube": cube_mesh}
    return builders[request.param]()


@pytest.fixture(scope="session")
def bunny(data_dir):
    return gwnrt.load(os.path.join(data_dir, "bunny.obj"))


@pytest.fixture(scope="session")
def bunny_holes(data_dir):
    return gwnrt.load(os.path.join(data_dir, "bunny_holes.obj"))

