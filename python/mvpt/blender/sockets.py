"""Reading a shader node's inputs: constant values, and the node that drives a linked input
(through reroutes)."""
from __future__ import annotations


def linked_node(socket):
    """The node whose output drives `socket`, past reroute nodes; None when unlinked."""
    while socket is not None and socket.is_linked:
        link = socket.links[0]
        if not link.is_valid or link.is_muted:
            return None
        node = link.from_node
        if node.bl_idname != "NodeReroute":
            return node
        socket = node.inputs[0]
    return None


def source_socket(socket):
    """The output socket that drives `socket` (past reroutes); None when unlinked."""
    while socket is not None and socket.is_linked:
        link = socket.links[0]
        node = link.from_node
        if node.bl_idname != "NodeReroute":
            return link.from_socket
        socket = node.inputs[0]
    return None


def value(node, name: str, default=0.0):
    """The constant value of input `name` (a float, or an RGB triple for colours), or `default`
    when the node has no such input."""
    socket = node.inputs.get(name)
    if socket is None or not hasattr(socket, "default_value"):
        return default
    v = socket.default_value
    if isinstance(v, (int, float)):
        return float(v)
    return tuple(float(c) for c in v)[:3]


def rgb(node, name: str):
    v = value(node, name, (0.0, 0.0, 0.0))
    return v if isinstance(v, tuple) else (v, v, v)


def is_linked(node, name: str) -> bool:
    socket = node.inputs.get(name)
    return socket is not None and linked_node(socket) is not None
