/* SPDX-License-Identifier: MIT */
/** @file mca/urdf.h
 * URDF loading (mca_model, start-up only): a URDF file through urdfdom into the chain model of mca/chain.h
 * that the real-time core (mca_core) computes on. Implemented in model/src/urdf_shim.cpp (C++17).
 */
#ifndef MCA_URDF_H
#define MCA_URDF_H

#include <stddef.h>

#include "mca/chain.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Load a serial chain from a URDF file (start-up only).
 * The chain runs from the URDF root link to @p tip_link (NULL: the single leaf link).
 * Revolute and continuous joints become joints; fixed joints are folded into the next origin
 * or into the tool pose. The capsule radius of each link is the radius of the <cylinder> (or
 * <sphere>) in the <collision> of the URDF link that the segment belongs to (the child link of
 * the segment's first joint); 0 when it has none.
 * @param[out] chain   filled on success, unchanged on error
 * @param[in]  path    URDF file
 * @param[in]  tip_link end-effector link name or NULL
 * @param[out] err     message naming the file and the element at fault (may be NULL)
 * @retval MCA_OK      loaded
 * @retval MCA_ENOENT  file missing or tip link not found
 * @retval MCA_EPARSE  not valid URDF, or a joint lacks limits / has a prismatic or planar type
 * @retval MCA_ERANGE  more than MCA_MAX_DOF joints
 * @retval MCA_EIO     file exists but cannot be read
 * @retval MCA_EINVAL  NULL chain or path
 * @retval MCA_ENOMEM  allocation failed inside the parser
 * Messages start with the path, then the line and element when known (docs/robots.md).
 * Not thread-safe: urdfdom's console output is captured through a process-wide handler.
 */
int mca_chain_load_urdf(mca_chain_t *chain, const char *path, const char *tip_link, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
