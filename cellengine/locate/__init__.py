"""Objects located on the bench by their ArUco markers in a camera's image (`cellengine
locate`, `cellengine run --locate`): the camera's pose from the world markers, each object
marker's centre on the plane of its object's top."""
