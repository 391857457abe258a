"""``pedenv inspect-bag``: what a ROS bag holds and what ``pedenv run --bag`` would use."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from pedenv.cli.app import app


@app.command("inspect-bag")
def inspect_bag(
    bag: Path = typer.Argument(..., help="rosbag2 folder, .mcap file or ROS 1 .bag."),
    image_topic: str | None = typer.Option(None, "--image-topic", help="The Image/CompressedImage topic."),
    camera_info_topic: str | None = typer.Option(None, "--camera-info-topic", help="The CameraInfo topic."),
    odometry_topic: str | None = typer.Option(None, "--odometry-topic", help="nav_msgs/Odometry for the ego."),
    world_frame: str | None = typer.Option(None, "--world-frame", help="The tf world frame."),
    vehicle_frame: str | None = typer.Option(None, "--vehicle-frame", help="The tf vehicle frame."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Print a bag's topics (types, counts, rates), its tf frames, and the topics and frames `run --bag` would use."""
    from pedenv.recordings.bag_inspect import format_inspection
    from pedenv.recordings.bag_inspect import inspect_bag as inspect
    from pedenv.recordings.bag_topics import BagOptions

    options = BagOptions(image_topic=image_topic, camera_info_topic=camera_info_topic, odometry_topic=odometry_topic,
                         world_frame=world_frame, vehicle_frame=vehicle_frame)
    summary = inspect(bag, options)
    typer.echo(json.dumps(summary, indent=2) if as_json else format_inspection(summary))
