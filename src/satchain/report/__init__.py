"""satchain.report"""
