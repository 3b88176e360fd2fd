"""Plugin machinery: hook specifications, component contracts and the registry."""
