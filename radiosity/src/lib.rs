//! Radiosity kernels: scene loading, meshing, octree ray casting, form factors, progressive
//! refinement and the sequential reference solver.
