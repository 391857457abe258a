"""Readers of real datasets' own file formats (KITTI, MOT17, nuScenes per-camera JSON).

Each reader returns frozen records of numpy arrays in the dataset's own conventions
(pixels, the dataset's camera frame, metres); adapters to pedenv's world frame build on
them. Bad files raise :class:`~pedenv.errors.InputError` naming the file and line.
"""
