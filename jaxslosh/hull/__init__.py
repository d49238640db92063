"""Closed hull and tank surfaces cut by a plane (docs/guide/large-angles.md): exact, differentiable clipping
of triangulated surfaces (`clip`), the box hull's surface (`box`), the GZ curve (`stability`)."""
