"""Closed hull and tank surfaces cut by a plane (PHYSICS section 5): exact, differentiable clipping
of triangulated surfaces (`clip`), the box hull's surface (`box`), the GZ curve (`stability`)."""
