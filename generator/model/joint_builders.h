/* joint_builders.h - the builder of each spatial joint kind, for joints.c's table of builders by kind. */
#ifndef MECHC_JOINT_BUILDERS_H
#define MECHC_JOINT_BUILDERS_H

#include "model.h"

/* A kind's rows, in joints.def's row order, as graph nodes. */
typedef void JointBuilder(Dag *d, const Joint *j, NodeId rows[JOINT_MAX_ROWS]);

/* The spatial family (joints_spatial.c); the planar builders are joints.c's own.
   A spatial row of joints.def needs its lower_KIND here and there. */
JointBuilder lower_S_SPHERICAL, lower_S_UNIVERSAL, lower_S_REVOLUTE, lower_S_CYLINDRICAL,
    lower_S_TRANSLATIONAL, lower_S_WELD, lower_S_DISTANCE, lower_S_POINTPLANE, lower_S_PARALLEL,
    lower_S_PERPENDICULAR, lower_S_ROLLING, lower_S_NORM, lower_S_CONTACT;

#endif
