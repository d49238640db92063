"""The tank liquid behind one contract (base.py AbstractLiquid), one sub-package per model: nodal/
(the stabilized and paper elements), face/ (the face-normal "rt" element), modal/ (reduced to modes),
multimodal/; the modes, damping, elastic walls and the block shared here (docs/design.md, "The
liquid")."""
