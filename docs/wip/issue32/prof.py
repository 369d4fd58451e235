#!/usr/bin/python3
"""End-point drift: position error of the last frame after aligning the first estimated pose on
the first ground-truth pose (docs/EVALUATION.md). usage: prof.py RUN_DIR DATA_DIR"""
import json, os, sys
import numpy as np

def quat_to_R(qx, qy, qz, qw):
    q = np.array([qw, qx, qy, qz]); q /= np.linalg.norm(q); w, x, y, z = q
    return np.array([[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)],
                     [2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)],
                     [2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]])

def read_tum(path):
    out = {}
    for line in open(path):
        if line.startswith('#') or not line.strip(): continue
        v = [float(x) for x in line.split()]
        T = np.eye(4); T[:3, :3] = quat_to_R(*v[4:8]); T[:3, 3] = v[1:4]
        out[round(v[0], 4)] = T
    return out

def read_kitti(path, times):
    out = {}
    for t, line in zip(times, open(path)):
        v = [float(x) for x in line.split()]
        T = np.eye(4); T[:3, :] = np.array(v).reshape(3, 4); out[round(t, 4)] = T
    return out

run, data = sys.argv[1], sys.argv[2]
est_path = os.path.join(run, 'CameraTrajectory.txt')
if os.path.exists(os.path.join(data, 'times.txt')):
    times = [float(l) for l in open(os.path.join(data, 'times.txt')) if l.strip()]
    gt = read_kitti(os.path.join(data, 'poses.txt'), times)
    first = open(est_path).readline().split()
    est = read_tum(est_path) if len(first) == 8 else read_kitti(est_path, times)
else:
    gt = read_tum(os.path.join(data, 'groundtruth.txt')); est = read_tum(est_path)
common = sorted(set(gt) & set(est))
t0, t1 = common[0], common[-1]
A = gt[t0] @ np.linalg.inv(est[t0])
drift = np.linalg.norm((A @ est[t1])[:3, 3] - gt[t1][:3, 3])
s = json.load(open(os.path.join(run, 'summary.json')))
ate = s.get('ate') or {}
print(json.dumps({'ate': (ate.get('translation_m') or {}).get('rmse'), 'drift_m': drift,
                  'loops': s.get('loops_closed', len(s.get('loops', []))),
                  'refused': s.get('loops_rejected'), 'frames': len(common)}))
