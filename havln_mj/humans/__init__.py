"""People in the scene: bodies, motions, activities, crowds, reactions and their drawing."""
