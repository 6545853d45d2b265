// What the task stages share (locate, resolve, field): the sample states, the
// slab's tets and tasks, and the decoding of one task. A task is one tet on
// one lattice slice, rows [firstRow, firstRow + VOX_RASTER_ROWS_PER_TASK).

layout(local_size_x = VOX_RASTER_TASK_GROUP_SIZE) in;

layout(std430, binding = VOX_RASTER_BINDING_STATE) buffer State { uint state[]; };
layout(std430, binding = VOX_RASTER_BINDING_TETS) readonly buffer Tets { RasterTet tets[]; };
layout(std430, binding = VOX_RASTER_BINDING_TASKS) readonly buffer Tasks { uint tasks[]; };
layout(push_constant) uniform Push { RasterTaskPush pc; };

struct Task {
  uint local;  // slab-local tet index
  uint slabZ;  // lattice slice within the slab
  int z;       // lattice slice
  int y0;      // rows y0..y1 of the tet's box
  int y1;
};

// False for the invocations past this dispatch's tasks.
bool taskOfInvocation(out Task task, out RasterTet t) {
  if (gl_GlobalInvocationID.x >= pc.taskCount) return false;
  const uint index = pc.taskBase + gl_GlobalInvocationID.x;
  task.local = tasks[2u * index];
  const uint zy = tasks[2u * index + 1u];
  t = tets[task.local];
  task.slabZ = zy & 0xFFFFu;
  task.z = int(pc.slabZ0 + task.slabZ);
  const int firstRow = int(zy >> 16);
  task.y0 = max(firstRow, t.loY);
  task.y1 = min(firstRow + VOX_RASTER_ROWS_PER_TASK - 1, t.hiY);
  return true;
}

uint rowStart(Task task, int y) { return (task.slabZ * pc.latticeNy + uint(y)) * pc.latticeNx; }
