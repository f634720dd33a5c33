"""Perception below the station: a depth camera's image -> the object's segmented point cloud in W.

:mod:`~catgrasp_drake.perception.object_cloud` holds the pure image/cloud
helpers and the LeafSystems the station wires behind every camera. The shape
estimator that fits the category model to such a cloud is a system of its
own (:mod:`catgrasp_drake.systems.shape_estimator`).
"""
