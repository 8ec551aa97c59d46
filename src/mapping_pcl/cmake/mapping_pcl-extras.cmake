# The exported mapping_pcl targets link PCL's common and filters libraries.
find_package(PCL REQUIRED COMPONENTS common filters)
