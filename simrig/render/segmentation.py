"""Segmentation renders in one draw call per camera: every actor's triangles in one vertex buffer.

pyrender draws a segmentation image one node at a time; with one node per actor most of a render's Python
time went to per-draw overhead (uniform look-ups, pose queries, buffer binds), and every render also read
and converted a depth image nobody used. Here all actors of a frame form one vertex buffer, each vertex
carrying its actor's slot number (an unsigned integer written into a ``GL_R32UI`` image, so ids need no
colour decoding) and its actor's pose; a camera is one ``glDrawElements`` and one read of the id image.

The answer is pyrender's, pixel for pixel (``tests/test_render_counts.py`` compares against counts stored
from the node-per-actor renderer): the same float32 vertex positions (taken from the pyrender meshes), the
same float64 poses, view and projection matrices rounded once to float32, the same shader expression
``P · V · M · pose · position`` with ``M`` the identity (multiplying by it is exact in floating point),
back-face culling, ``GL_LESS`` depth test on a 24-bit depth buffer, one sample per pixel (pyrender
switches multisampling off for segmentation), and actors drawn farthest first like pyrender's node sort,
so even ties at equal depth resolve the same way.

Runs in the OpenGL context of :func:`.scene.offscreen_renderer`, which the caller makes current.
"""

from __future__ import annotations

import ctypes

import numpy as np
from OpenGL import GL
from OpenGL.GL import shaders

_VERTEX_SHADER = """
#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in mat4 pose;
layout(location = 5) in uint slot;
uniform mat4 P;
uniform mat4 V;
uniform mat4 M;
flat out uint frag_slot;
void main()
{
    gl_Position = P * V * M * pose * vec4(position, 1.0);
    frag_slot = slot;
}
"""
_FRAGMENT_SHADER = """
#version 330 core
flat in uint frag_slot;
out uint slot;
void main()
{
    slot = frag_slot;
}
"""
_FLOATS_PER_VERTEX = 3 + 16  # position, pose (column-major, as OpenGL reads a mat4 attribute)


class SegmentationPass:
    """Actor-id images of one frame's actors, one draw call per camera (module docstring).

    :meth:`set_actors` uploads the frame; :meth:`counts` renders one camera and returns each actor's pixels.
    ``meshes`` gives, per mesh key, the ``(K, 3)`` float32 triangle-soup vertex positions of the unit mesh.
    """

    def __init__(self, meshes: dict[object, np.ndarray]):
        self._meshes = {key: np.ascontiguousarray(positions, dtype=np.float32) for key, positions in meshes.items()}
        self._program = shaders.compileProgram(
            shaders.compileShader(_VERTEX_SHADER, GL.GL_VERTEX_SHADER),
            shaders.compileShader(_FRAGMENT_SHADER, GL.GL_FRAGMENT_SHADER),
        )
        self._uniforms = {name: GL.glGetUniformLocation(self._program, name) for name in ("P", "V", "M")}
        self._vao = GL.glGenVertexArrays(1)
        self._vertex_buffer, self._slot_buffer, self._index_buffer = GL.glGenBuffers(3)
        GL.glBindVertexArray(self._vao)
        stride = 4 * _FLOATS_PER_VERTEX
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._vertex_buffer)
        GL.glEnableVertexAttribArray(0)
        GL.glVertexAttribPointer(0, 3, GL.GL_FLOAT, GL.GL_FALSE, stride, ctypes.c_void_p(0))
        for column in range(4):
            GL.glEnableVertexAttribArray(1 + column)
            GL.glVertexAttribPointer(
                1 + column, 4, GL.GL_FLOAT, GL.GL_FALSE, stride, ctypes.c_void_p(4 * (3 + 4 * column))
            )
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._slot_buffer)
        GL.glEnableVertexAttribArray(5)
        GL.glVertexAttribIPointer(5, 1, GL.GL_UNSIGNED_INT, 4, ctypes.c_void_p(0))
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, self._index_buffer)
        GL.glBindVertexArray(0)
        self._framebuffers: dict[tuple[int, int], tuple[int, np.ndarray]] = {}
        self._blocks = np.zeros((0, 2), dtype=np.int64)  # first vertex, vertex count per actor
        self._centres = np.zeros((0, 3))

    def set_actors(self, keys: list, poses: np.ndarray) -> None:
        """Upload the frame: actor ``i`` is mesh ``keys[i]`` placed by the ``(4, 4)`` float64 ``poses[i]``
        (scale, rotation and translation, in the render frame) and is counted as slot ``i``."""
        sizes = np.array([len(self._meshes[key]) for key in keys], dtype=np.int64)
        starts = np.concatenate([[0], np.cumsum(sizes)])
        self._blocks = np.stack([starts[:-1], sizes], axis=1)
        self._centres = np.asarray(poses, dtype=float)[:, :3, 3] if len(keys) else np.zeros((0, 3))
        vertices = np.empty((int(starts[-1]), _FLOATS_PER_VERTEX), dtype=np.float32)
        if len(keys):
            vertices[:, :3] = np.concatenate([self._meshes[key] for key in keys])
            columns = np.transpose(np.asarray(poses, dtype=float), (0, 2, 1)).reshape(-1, 16)
            vertices[:, 3:] = np.repeat(columns, sizes, axis=0)  # float64 → float32 once, like pyrender's uniform
        slots = np.repeat(np.arange(1, len(keys) + 1, dtype=np.uint32), sizes)  # 0 is the background
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._vertex_buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, vertices.nbytes, vertices, GL.GL_STREAM_DRAW)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._slot_buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, slots.nbytes, slots, GL.GL_STREAM_DRAW)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, 0)

    def _framebuffer(self, width: int, height: int) -> tuple[int, np.ndarray]:
        """An id image (``GL_R32UI``) with a 24-bit depth buffer at this resolution, and its read-back array."""
        if (width, height) not in self._framebuffers:
            colour, depth = GL.glGenRenderbuffers(2)
            GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, colour)
            GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_R32UI, width, height)
            GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, depth)
            GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_DEPTH_COMPONENT24, width, height)
            framebuffer = GL.glGenFramebuffers(1)
            GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
            GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_RENDERBUFFER, colour)
            GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_RENDERBUFFER, depth)
            status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
            if status != GL.GL_FRAMEBUFFER_COMPLETE:
                raise RuntimeError(f"segmentation framebuffer {width}×{height} incomplete (status {status:#x})")
            self._framebuffers[(width, height)] = (framebuffer, np.empty((height, width), dtype=np.uint32))
        return self._framebuffers[(width, height)]

    def counts(self, camera_pose: np.ndarray, projection: np.ndarray, width: int, height: int) -> np.ndarray:
        """``(N,)`` pixels showing each actor (slot order) in a ``width`` × ``height`` render from a camera
        at the float64 ``camera_pose`` (camera to render frame, OpenGL axes) with ``projection``."""
        n = len(self._blocks)
        framebuffer, ids = self._framebuffer(width, height)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
        GL.glViewport(0, 0, width, height)
        GL.glClearBufferuiv(GL.GL_COLOR, 0, np.zeros(4, dtype=np.uint32))
        GL.glClearBufferfv(GL.GL_DEPTH, 0, np.ones(1, dtype=np.float32))
        if n:
            # pyrender draws opaque nodes farthest first (Renderer._sorted_mesh_nodes): same order here.
            order = np.argsort(-np.linalg.norm(self._centres - camera_pose[:3, 3], axis=1), kind="stable")
            first, size = self._blocks[order, 0], self._blocks[order, 1]
            indices = (np.repeat(first - np.cumsum(size) + size, size) + np.arange(size.sum())).astype(np.uint32)
            GL.glEnable(GL.GL_DEPTH_TEST)
            GL.glDepthMask(GL.GL_TRUE)
            GL.glDepthFunc(GL.GL_LESS)
            GL.glDepthRange(0.0, 1.0)
            GL.glEnable(GL.GL_CULL_FACE)
            GL.glCullFace(GL.GL_BACK)
            GL.glDisable(GL.GL_BLEND)
            GL.glPolygonMode(GL.GL_FRONT_AND_BACK, GL.GL_FILL)
            GL.glUseProgram(self._program)
            GL.glUniformMatrix4fv(self._uniforms["P"], 1, GL.GL_TRUE, projection.astype(np.float32))
            GL.glUniformMatrix4fv(self._uniforms["V"], 1, GL.GL_TRUE, np.linalg.inv(camera_pose).astype(np.float32))
            GL.glUniformMatrix4fv(self._uniforms["M"], 1, GL.GL_TRUE, np.eye(4, dtype=np.float32))
            GL.glBindVertexArray(self._vao)
            GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, indices.nbytes, indices, GL.GL_STREAM_DRAW)
            GL.glDrawElements(GL.GL_TRIANGLES, len(indices), GL.GL_UNSIGNED_INT, ctypes.c_void_p(0))
            GL.glBindVertexArray(0)
            GL.glUseProgram(0)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
        GL.glReadPixels(0, 0, width, height, GL.GL_RED_INTEGER, GL.GL_UNSIGNED_INT, ids)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        return np.bincount(ids.ravel(), minlength=n + 1)[1:].astype(np.int64)
