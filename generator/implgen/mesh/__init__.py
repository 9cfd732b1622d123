"""`implgen mesh`: watertight triangle meshes of a shape, every grid-line crossing solved exactly (docs/mesh.md)."""
