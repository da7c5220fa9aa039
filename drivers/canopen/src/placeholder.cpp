// Replaced as the package grows.
namespace saw::canopen {}
